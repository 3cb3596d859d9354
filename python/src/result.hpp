#pragma once
// A SegmentationResult as the Python dict of docs/python.md ("indices", "scores", "log_scales",
// "diagnostics"); shared by vcar.segment and vcar.Reselection.select.
#include "common.hpp"
#include "vcar/algo/pipeline.hpp"

namespace vcar::python {

py::dict result_dict(SegmentationResult&& r, const VcarParams& params);

}  // namespace vcar::python
