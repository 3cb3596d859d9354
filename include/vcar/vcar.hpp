#pragma once
// Umbrella header: every public header of vcar, nothing else.
#include "vcar/core/error.hpp"
#include "vcar/core/rotation.hpp"
#include "vcar/core/gaussian_scene.hpp"
#include "vcar/core/camera.hpp"
#include "vcar/core/image.hpp"
#include "vcar/core/parallel.hpp"
#include "vcar/core/projection.hpp"
#include "vcar/concepts/renderer.hpp"
#include "vcar/concepts/segmenter.hpp"
