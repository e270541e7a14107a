#pragma once
// The state-dict level of ogmm/authors_checkpoint.hpp: the functions that take or return the
// authors' tensors themselves (LibTorch types), for ogmm/ and its tests.
#include <nlohmann/json.hpp>
#include <string>

#include "ogmm/authors_checkpoint.hpp"
#include "ogmm/torch_save_reader.hpp"

namespace regbench::ogmm {

/// The regbench model config (zoo form, with "arch", "name" and "train") the state dict
/// `tensors` of file `file` describes. Throws std::runtime_error naming the file and tensor.
nlohmann::json InferAuthorsConfig(const StateDict& tensors, const std::string& file,
                                  const ImportOptions& options);

/// The state dict the authors' module `to` ("deepgmr" | "ogmm") would have for the checkpoint
/// in `dir`, in their key order. Throws naming the folder when it is of another family.
StateDict ExportAuthorsStateDict(const std::string& dir, const std::string& to);

}  // namespace regbench::ogmm
