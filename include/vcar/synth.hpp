#pragma once
// Umbrella header of vcar::synth: vcar::io plus the synthetic world (scenes with exact ground
// truth, camera rigs, the oracle segmenter, dataset export) and the evaluation metrics.
#include "vcar/io.hpp"

#include "vcar/synth/world.hpp"
#include "vcar/synth/rigs.hpp"
#include "vcar/synth/ground_truth.hpp"
#include "vcar/synth/mask_ops.hpp"
#include "vcar/synth/rendered_labels.hpp"
#include "vcar/synth/sam_failures.hpp"
#include "vcar/synth/oracle_segmenter.hpp"
#include "vcar/synth/prompt.hpp"
#include "vcar/synth/object_prompts.hpp"
#include "vcar/synth/world_json.hpp"
#include "vcar/synth/dataset.hpp"
#include "vcar/synth/stage.hpp"
#include "vcar/synth/stage_json.hpp"

#include "vcar/eval/mask_metrics.hpp"
#include "vcar/eval/boundary_metrics.hpp"
#include "vcar/eval/selection_metrics.hpp"
#include "vcar/eval/aggregate.hpp"
