#pragma once
// Training recipes several families share (the "train" object of a zoo config; TrainConfig in
// networks/training/train.hpp). JSON only: no LibTorch.
#include <nlohmann/json.hpp>

namespace regbench::networks {

/// The OGMM authors' training recipe (their DeepGMR baseline shares it): Adam 1e-4 with weight
/// decay 1e-4, MultiStepLR at epochs 75/150/200 of 450 (x0.1), batch 24. Milestones are
/// fractions of the run so they scale with a shorter budget.
nlohmann::json OgmmTrainingRecipe();

/// The CPU campaign recipe of the reduced configs (ogmm-small, deepgmr-small, rienet): the
/// authors' recipe above with lr 1e-3 and batch 8, a plan of 40 epochs of 512 pairs (on a CPU
/// the authors' lr and batch take weeks to move; the multistep drops bring lr to 1e-4 after
/// 1/6 of the plan).
nlohmann::json CampaignTrainingRecipe();

}  // namespace regbench::networks
