#pragma once
// Umbrella header of vcar::vcar: core, concepts, algorithms and the CPU backend. Needs Eigen and
// xsimd (or VCAR_SIMD_SCALAR) only: never nlohmann_json, stb or POSIX headers (tested by
// tests/consumer). The other targets have their own: <vcar/io.hpp> (vcar::io),
// <vcar/synth.hpp> (vcar::synth, with eval), <vcar/baselines.hpp> (vcar::baselines).
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
#include "vcar/core/simd.hpp"

#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
#include "vcar/concepts/multi_segmenter.hpp"

#include "vcar/algo/params.hpp"
#include "vcar/algo/visibility_voting.hpp"
#include "vcar/algo/robust_sphere.hpp"
#include "vcar/algo/view_completeness.hpp"
#include "vcar/algo/spiral_sampler.hpp"
#include "vcar/algo/abr_geometry.hpp"
#include "vcar/algo/boundary_distance.hpp"
#include "vcar/algo/abr_kernel.hpp"
#include "vcar/algo/abr_state.hpp"
#include "vcar/algo/boundary_refinement.hpp"
#include "vcar/algo/incremental_refinement.hpp"
#include "vcar/algo/pipeline.hpp"
#include "vcar/algo/segment_objects.hpp"
#include "vcar/algo/reselection.hpp"
#include "vcar/algo/prompt_lift.hpp"

#include "vcar/backends/cpu/tiled_renderer.hpp"
