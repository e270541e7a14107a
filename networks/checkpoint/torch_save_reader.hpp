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

#include <cstddef>
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

/// The memory budget of one read (docs/learned-methods.md, "Reader limits"): 2 GiB, twenty
/// times the largest authors' checkpoint regbench imports. A file larger than it, a zip record
/// that declares more, storages that declare more in all, or tensors that would take more in
/// all are refused naming the file, before anything of that size is allocated.
constexpr std::uint64_t kMaxTorchSaveBytes = std::uint64_t{2} << 30;
/// A zip record other than a storage (data.pkl, version) and the zip's central directory may
/// hold at most 64 MiB (a state dict of 20,000 tensors pickles to under 2 MB).
constexpr std::uint64_t kMaxTorchSavePickleBytes = std::uint64_t{64} << 20;
/// The pickle may make at most this many objects (and hold as many memo entries, stack entries
/// and marks): a state dict takes about 11 per tensor, so 524,288 is 40,000 tensors, forty
/// times the largest authors' file.
constexpr std::size_t kMaxPickleObjects = std::size_t{1} << 19;

/// Reads `path`, opened once without blocking and checked as opened: a folder, a FIFO or a
/// device is refused by name (never waited on), as is a file larger than kMaxTorchSaveBytes
/// (before it is read) or one that cannot be read. A zip archive is read lazily: its central
/// directory, then the records it needs, each checked against the file's size and the budgets
/// above before it is read or inflated (inflating stops at the declared size); a legacy file is
/// read whole (it is at most kMaxTorchSaveBytes). Errors name `path`.
TorchSaveContents ReadTorchSaveFile(const std::string& path);
/// Same for bytes in memory (fuzzing, tests); errors name `name`.
TorchSaveContents ReadTorchSaveBytes(const std::string& bytes, const std::string& name);

/// Checks the zip archive `path` (a LibTorch-written file: regbench's weights.pt) against the
/// same limits before LibTorch's reader loads it: its size, and every record's declared size
/// against the file and kMaxTorchSaveBytes (in all). Throws std::runtime_error naming `path`.
void CheckTorchZipSizes(const std::string& path);

/// Serialises a state dict in PyTorch's zip format (what `torch.save(sd)` of PyTorch >= 1.6
/// writes; `torch.load` returns a dict of str -> Tensor in this order). Tensors are made
/// contiguous CPU tensors.
std::string WriteTorchSaveZip(const StateDict& tensors);

using regbench::Sha256File;
using regbench::Sha256Hex;

}  // namespace regbench::networks
