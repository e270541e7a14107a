#pragma once
// The versions of the libraries a method's call can run on, for the timing provenance of every
// result row (`machine.libraries`, runners/runner.cpp) and the captions that show it.
#include <nlohmann/json.hpp>

namespace regbench {

/// {"eigen": "3.4.0", "open3d": "0.16.1", "libtorch": "1.13.0" or "not built",
/// "blas": the BLAS under LibTorch (networks::BlasDescription) or the classical methods' "none
/// (Eigen's own kernels)" when LibTorch is not built}. Compile-time versions of the headers
/// this binary was built with; the BLAS is read at run time.
nlohmann::json LibraryVersions();

}  // namespace regbench
