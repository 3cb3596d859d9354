#pragma once
// Umbrella header of vcar::opencv (OpenCV core and imgproc): the segmenters built on OpenCV.
// vcar::vcar never includes it.
#include "vcar/opencv/grabcut_segmenter.hpp"
