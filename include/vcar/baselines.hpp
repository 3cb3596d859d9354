#pragma once
// Umbrella header of vcar::baselines: vcar::vcar plus the peers' methods behind the same
// interfaces (needs nanoflann and Boost.Graph headers).
#include "vcar/vcar.hpp"

#include "vcar/baselines/inputs.hpp"
#include "vcar/baselines/view_contributions.hpp"
#include "vcar/baselines/contribution_walk.hpp"
#include "vcar/baselines/knn_graph.hpp"
#include "vcar/baselines/naive_voting.hpp"
#include "vcar/baselines/sagd.hpp"
#include "vcar/baselines/flashsplat.hpp"
#include "vcar/baselines/gaussian_cut.hpp"
#include "vcar/baselines/ludvig.hpp"
#include "vcar/baselines/lbg.hpp"
#include "vcar/baselines/isegman.hpp"
