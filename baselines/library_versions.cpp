#include "baselines/library_versions.hpp"

#include <open3d/Open3DConfig.h>

#include <Eigen/Core>
#include <string>

// Defined for this file when networks/ is built (baselines/CMakeLists.txt); LibTorch itself
// stays inside networks/.
#ifdef REGBENCH_LIBRARY_VERSIONS_TORCH
#include "networks/gemm_floor.hpp"
#endif

namespace regbench {

nlohmann::json LibraryVersions() {
    nlohmann::json v;
    v["eigen"] = std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) +
                 "." + std::to_string(EIGEN_MINOR_VERSION);
    v["open3d"] = OPEN3D_VERSION;
#ifdef REGBENCH_LIBRARY_VERSIONS_TORCH
    v["libtorch"] = networks::LibTorchVersion();
    v["blas"] = networks::BlasDescription();
#else
    v["libtorch"] = "not built";
    v["blas"] = "none (Eigen's own kernels)";
#endif
    return v;
}

}  // namespace regbench
