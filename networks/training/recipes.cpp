#include "networks/training/recipes.hpp"

namespace regbench::networks {

nlohmann::json OgmmTrainingRecipe() {
    return {{"lr", 1e-4},
            {"weight_decay", 1e-4},
            {"batch", 24},
            {"epochs", 450},
            {"pairs_per_epoch", 4096},
            {"schedule", "multistep"},
            {"milestones", {75.0 / 450, 150.0 / 450, 200.0 / 450}},
            {"lr_gamma", 0.1}};
}

nlohmann::json CampaignTrainingRecipe() {
    nlohmann::json train = OgmmTrainingRecipe();
    train["lr"] = 1e-3;
    train["batch"] = 8;
    train["pairs_per_epoch"] = 512;
    train["epochs"] = 40;
    return train;
}

}  // namespace regbench::networks
