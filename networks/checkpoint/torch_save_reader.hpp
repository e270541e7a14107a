#pragma once
// Reads PyTorch `torch.save(state_dict)` files natively (no Python): the zip archive of PyTorch
// >= 1.6 (data.pkl + data/<key> records) and the legacy stream of PyTorch <= 1.5 (five pickles:
// magic number, protocol version, sys_info, the object with persistent ids for its storages,
// the sorted storage keys; then each storage as an int64 element count and its raw bytes).
//
// The pickle is run by a small restricted interpreter written for this format: it knows the
// opcodes pickle protocols 2-4 use for a state dict and accepts only the globals a plain state
// dict needs (collections.OrderedDict, torch._utils._rebuild_tensor{,_v2}, _rebuild_parameter,
// torch.*Storage), plus the numpy scalar a training checkpoint may hold beside its state dict
// (numpy.core.multiarray.scalar, numpy.dtype, _codecs.encode: read as inert bytes, never
// called; RIENet's files store {"model", "optimizer", "epoch", "best_result": np.float64}).
// Anything else (a pickled class, a TorchScript archive, a truncated or
// corrupt file) is refused with a std::runtime_error naming the file; it never executes code.
// Objects live in one arena (indices, no owning pointers), so hostile nesting cannot overflow
// the stack. Also a zip-format writer of a
// state dict.
#include <torch/torch.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/sha256.hpp"

namespace regbench::networks {

/// One state dict in file order.
using StateDict = std::vector<std::pair<std::string, torch::Tensor>>;

struct TorchSaveContents {
    StateDict tensors;
    std::string format;   ///< "zip" or "legacy"
    std::string wrapper;  ///< "" or the key ("state_dict", "model", ...) the dict was found under
    std::string sha256;   ///< of the bytes read (ReadTorchSaveFile only; "" from bytes)
    std::uint64_t bytes = 0;  ///< how many were read (ReadTorchSaveFile only)
};

/// The largest file ReadTorchSaveFile reads (it reads the file whole): 2 GiB, twenty times the
/// largest authors' checkpoint regbench imports. A larger file is refused naming it.
constexpr std::uint64_t kMaxTorchSaveFileBytes = std::uint64_t{2} << 30;

/// Reads `path`, opened once without blocking and checked as opened: a folder, a FIFO or a
/// device is refused by name (never waited on), as is a file larger than
/// kMaxTorchSaveFileBytes (before it is read) or one that cannot be read. Errors name `path`.
TorchSaveContents ReadTorchSaveFile(const std::string& path);
/// Same for bytes in memory (fuzzing, tests); errors name `name`.
TorchSaveContents ReadTorchSaveBytes(const std::string& bytes, const std::string& name);

/// Serialises a state dict in PyTorch's zip format (what `torch.save(sd)` of PyTorch >= 1.6
/// writes; `torch.load` returns a dict of str -> Tensor in this order). Tensors are made
/// contiguous CPU tensors.
std::string WriteTorchSaveZip(const StateDict& tensors);

using regbench::Sha256File;
using regbench::Sha256Hex;

}  // namespace regbench::networks
