#pragma once
// Umbrella header: every public header of vcar::vcar, nothing else. The peers' methods
// (vcar/baselines/*.hpp) are not included: they need nanoflann and Boost (target vcar::baselines).
#include "vcar/core/error.hpp"
#include "vcar/core/rotation.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/rle_mask.hpp"
#include "vcar/core/distance_transform.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/projection.hpp"
#include "vcar/core/spherical_harmonics.hpp"

#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"

#include "vcar/algo/params.hpp"
#include "vcar/algo/visibility_voting.hpp"
#include "vcar/algo/robust_sphere.hpp"
#include "vcar/algo/view_completeness.hpp"
#include "vcar/algo/spiral_sampler.hpp"
#include "vcar/algo/boundary_distance.hpp"
#include "vcar/algo/boundary_refinement.hpp"
#include "vcar/algo/pipeline.hpp"

#include "vcar/backends/cpu/tiled_renderer.hpp"

#include "vcar/io/atomic_file.hpp"
#include "vcar/io/ply.hpp"
#include "vcar/io/colmap.hpp"
#include "vcar/io/cameras_json.hpp"
#include "vcar/io/transforms_json.hpp"
#include "vcar/io/cameras.hpp"
#include "vcar/io/image_file.hpp"
#include "vcar/io/mask_folder_segmenter.hpp"
#include "vcar/io/external_segmenter.hpp"

#include "vcar/synth/world.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/prompt.hpp"
#include "vcar/synth/dataset.hpp"

#include "vcar/eval/mask_metrics.hpp"
#include "vcar/eval/boundary_metrics.hpp"
#include "vcar/eval/selection_metrics.hpp"
#include "vcar/eval/aggregate.hpp"
