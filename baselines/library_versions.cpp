#include "baselines/library_versions.hpp"

#include <open3d/Open3DConfig.h>

#include <Eigen/Core>
#include <string>

// LibTorch's headers are on the include path only when networks/ is built (REGBENCH_WITH_TORCH).
#if __has_include(<torch/version.h>)
#include <torch/version.h>

#include "networks/gemm_floor.hpp"
#define REGBENCH_LIBRARY_VERSIONS_TORCH 1
#endif

namespace regbench {

nlohmann::json LibraryVersions() {
    nlohmann::json v;
    v["eigen"] = std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) +
                 "." + std::to_string(EIGEN_MINOR_VERSION);
    v["open3d"] = OPEN3D_VERSION;
#ifdef REGBENCH_LIBRARY_VERSIONS_TORCH
    v["libtorch"] = TORCH_VERSION;
    v["blas"] = networks::BlasDescription();
#else
    v["libtorch"] = "not built";
    v["blas"] = "none (Eigen's own kernels)";
#endif
    return v;
}

}  // namespace regbench
