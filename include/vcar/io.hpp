#pragma once
// Umbrella header of vcar::io: vcar::vcar plus the readers and writers (Inria PLY, PlayCanvas
// compressed PLY, SPZ through zlib and zstd, .splat, SuperSplat state PLY, COLMAP,
// cameras.json, transforms.json, PNG/JPEG masks and images through stb, JSON through
// nlohmann_json), atomic writes, the mask-folder segmenter and the external (POSIX) segmenter.
#include "vcar/vcar.hpp"

#include "vcar/io/atomic_file.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/compact_values.hpp"
#include "vcar/io/compressed_ply.hpp"
#include "vcar/io/spz.hpp"
#include "vcar/io/splat_file.hpp"
#include "vcar/io/scene_file.hpp"
#include "vcar/io/state_ply.hpp"
#include "vcar/io/label_ply.hpp"
#include "vcar/io/selection_identity.hpp"
#include "vcar/io/selection_file.hpp"
#include "vcar/io/diagnostics_json.hpp"
#include "vcar/io/colmap.hpp"
#include "vcar/io/cameras_json.hpp"
#include "vcar/io/transforms_json.hpp"
#include "vcar/io/cameras.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/json_file.hpp"
#include "vcar/io/params_text.hpp"
#include "vcar/io/mask_folder_segmenter.hpp"
#include "vcar/io/external_segmenter.hpp"
