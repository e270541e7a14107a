#include "networks/checkpoint/torch_save_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <caffe2/serialize/inline_container.h>
#include <caffe2/serialize/in_memory_adapter.h>
#include <caffe2/serialize/read_adapter_interface.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>


namespace regbench::networks {
namespace {

[[noreturn]] void Fail(const std::string& name, const std::string& what) {
    throw std::runtime_error(name + ": " + what);
}

// --------------------------------------------------------------------------- file access

/// The opened file, read with pread where asked (LibTorch's zip reader reads through it).
class FdReadAdapter final : public caffe2::serialize::ReadAdapterInterface {
public:
    FdReadAdapter(int fd, std::uint64_t size, std::string name)
        : fd_(fd), size_(size), name_(std::move(name)) {}
    size_t size() const override { return size_; }
    size_t read(uint64_t pos, void* buf, size_t n, const char* /*what*/) const override {
        auto* out = static_cast<char*>(buf);
        size_t done = 0;
        while (done < n) {
            const ssize_t got = ::pread(fd_, out + done, n - done, static_cast<off_t>(pos + done));
            if (got < 0 && errno == EINTR) continue;
            // An EIO (/proc/self/mem) ended as a bare "basic_filebuf::underflow".
            if (got < 0) Fail(name_, std::string("read error: ") + std::strerror(errno));
            if (got == 0) Fail(name_, "ends early: the file shrank while it was read");
            done += static_cast<size_t>(got);
        }
        return n;
    }

private:
    int fd_;
    std::uint64_t size_;
    std::string name_;
};

std::string ReadAt(const caffe2::serialize::ReadAdapterInterface& in, uint64_t pos, size_t n) {
    std::string s(n, '\0');
    if (n > 0) in.read(pos, &s[0], n);
    return s;
}

uint64_t Le(const std::string& b, size_t at, int n) {
    uint64_t v = 0;
    for (int j = n - 1; j >= 0; --j) v = (v << 8) | static_cast<uint8_t>(b[at + j]);
    return v;
}

// ----------------------------------------------------------------- zip central directory

/// What the central directory declares of one record.
struct ZipEntry {
    uint16_t method = 0;
    uint64_t compressed = 0, size = 0, offset = 0;
};

/// Deflate expands at most 1032 to 1 (zlib's technical details, "Maximum compression
/// factor"): a record that declares more than that from its compressed bytes is lying.
constexpr uint64_t kMaxDeflateRatio = 1032;

/// The central directory of the zip archive `in` (APPNOTE.TXT 4.3.12-4.3.16, zip64 included),
/// every record checked against the file before anything it declares is read: a record lies
/// inside the file, a stored one declares as many bytes as it holds, a deflated one no more
/// than 1032 times its compressed bytes, and records other than storages (data/...) at most
/// kMaxTorchSavePickleBytes each. Records by name; `first` receives the first one's name.
std::map<std::string, ZipEntry> ReadZipDirectory(const caffe2::serialize::ReadAdapterInterface& in,
                                                 const std::string& name, std::string* first) {
    const uint64_t file = in.size();
    const auto bad = [&](const std::string& what) { Fail(name, "corrupt zip archive: " + what); };
    // The end-of-central-directory record: 22 bytes and a comment of at most 65535.
    const uint64_t tail_size = std::min<uint64_t>(file, 22 + 65535);
    const std::string tail = ReadAt(in, file - tail_size, tail_size);
    size_t eocd = std::string::npos;
    for (size_t j = tail.size() >= 22 ? tail.size() - 22 + 1 : 0; j-- > 0;) {
        if (Le(tail, j, 4) == 0x06054b50) {
            eocd = j;
            break;
        }
    }
    if (eocd == std::string::npos) bad("no end-of-central-directory record");
    uint64_t entries = Le(tail, eocd + 10, 2);
    uint64_t cd_size = Le(tail, eocd + 12, 4);
    uint64_t cd_offset = Le(tail, eocd + 16, 4);
    const uint64_t eocd_at = file - tail_size + eocd;
    if (entries == 0xffff || cd_size == 0xffffffff || cd_offset == 0xffffffff) {
        // zip64: a locator 20 bytes before, pointing at the zip64 end record.
        if (eocd_at < 20) bad("zip64 locator missing");
        const std::string loc = ReadAt(in, eocd_at - 20, 20);
        if (Le(loc, 0, 4) != 0x07064b50) bad("zip64 locator missing");
        const uint64_t at = Le(loc, 8, 8);
        if (at > file || file - at < 56) bad("zip64 end record outside the file");
        const std::string z = ReadAt(in, at, 56);
        if (Le(z, 0, 4) != 0x06064b50) bad("zip64 end record missing");
        entries = Le(z, 32, 8);
        cd_size = Le(z, 40, 8);
        cd_offset = Le(z, 48, 8);
    }
    if (cd_offset > file || cd_size > file - cd_offset) {
        bad("its central directory lies outside the file");
    }
    if (cd_size > kMaxTorchSavePickleBytes) {
        bad("central directory of " + std::to_string(cd_size) + " bytes, more than the " +
            std::to_string(kMaxTorchSavePickleBytes) + " regbench reads");
    }
    const std::string cd = ReadAt(in, cd_offset, cd_size);
    std::map<std::string, ZipEntry> out;
    size_t p = 0;
    for (uint64_t k = 0; k < entries; ++k) {
        if (cd.size() - p < 46 || Le(cd, p, 4) != 0x02014b50) bad("truncated central directory");
        ZipEntry e;
        e.method = static_cast<uint16_t>(Le(cd, p + 10, 2));
        e.compressed = Le(cd, p + 20, 4);
        e.size = Le(cd, p + 24, 4);
        e.offset = Le(cd, p + 42, 4);
        const size_t name_len = Le(cd, p + 28, 2), extra_len = Le(cd, p + 30, 2);
        const size_t record = 46 + name_len + extra_len + Le(cd, p + 32, 2);
        if (cd.size() - p < record) bad("truncated central directory");
        const std::string rname = cd.substr(p + 46, name_len);
        if (k == 0) *first = rname;
        // zip64 extended information (header 1): 8-byte values for the fields set to ~0.
        for (size_t x = p + 46 + name_len; x + 4 <= p + 46 + name_len + extra_len;) {
            const uint64_t id = Le(cd, x, 2), len = Le(cd, x + 2, 2);
            if (x + 4 + len > p + 46 + name_len + extra_len) bad("malformed extra field");
            if (id == 1) {
                size_t f = x + 4;
                for (uint64_t* v : {&e.size, &e.compressed, &e.offset}) {
                    if (*v != 0xffffffff) continue;
                    if (f + 8 > x + 4 + len) bad("malformed zip64 field of " + rname);
                    *v = Le(cd, f, 8);
                    f += 8;
                }
            }
            x += 4 + len;
        }
        p += record;
        const std::string what = "record " + rname + " ";
        if (e.method != 0 && e.method != 8) {
            Fail(name, what + "is compressed with zip method " + std::to_string(e.method) +
                           "; torch.save files hold stored or deflated records only");
        }
        if (e.offset > cd_offset || e.compressed > cd_offset - e.offset) {
            Fail(name, what + "declares " + std::to_string(e.compressed) + " bytes at offset " +
                           std::to_string(e.offset) + ", beyond the file's " +
                           std::to_string(file) + " bytes");
        }
        if (e.method == 0 && e.size != e.compressed) {
            Fail(name, what + "is stored but declares " + std::to_string(e.size) +
                           " bytes for the " + std::to_string(e.compressed) + " it holds");
        }
        if (e.method == 8 && e.size / kMaxDeflateRatio > e.compressed) {
            Fail(name, what + "declares " + std::to_string(e.size) + " bytes from " +
                           std::to_string(e.compressed) +
                           " deflated ones, more than deflate can give (1032 to 1)");
        }
        if (e.size > kMaxTorchSaveBytes) {
            Fail(name, what + "declares " + std::to_string(e.size) + " bytes, more than the " +
                           std::to_string(kMaxTorchSaveBytes) + " a checkpoint may hold");
        }
        const size_t slash = rname.find('/');
        const bool storage = slash != std::string::npos && rname.compare(slash, 6, "/data/") == 0;
        if (!storage && e.size > kMaxTorchSavePickleBytes) {
            Fail(name, what + "declares " + std::to_string(e.size) + " bytes, more than the " +
                           std::to_string(kMaxTorchSavePickleBytes) +
                           " a pickle or header record may have");
        }
        out[rname] = e;
    }
    return out;
}

// ------------------------------------------------------------------------- pickle objects

enum class Kind {
    kNone,
    kBool,
    kInt,
    kBigInt,
    kFloat,
    kStr,
    kBytes,
    kTuple,
    kList,
    kDict,
    kGlobal,
    kStorageType,
    kStorage,
    kTensor,
    kNumpyDtype,  // numpy.dtype(str, False, True): s = the dtype string ("f8")
    kNumpyScalar  // numpy scalar (a training checkpoint's metric): s = its raw bytes, unread
};

struct Obj {
    Kind kind = Kind::kNone;
    int64_t i = 0;           // kInt, kBool; kStorage: numel; kTensor: storage offset
    double f = 0.0;          // kFloat
    std::string s;           // kStr, kBytes, kBigInt (little-endian bytes), kGlobal
                             // ("module.name"), kStorage: key
    std::vector<int> items;  // kTuple, kList; kDict: key, value, key, value...
    c10::ScalarType dtype = c10::ScalarType::Float;  // kStorageType, kStorage, kTensor
    int storage = -1;                                // kTensor: its kStorage object
    std::vector<int64_t> sizes, strides;             // kTensor
};

/// Most dimensions a tensor of a state dict may have.
constexpr size_t kMaxDims = 16;

/// The tensor types a state dict may hold; each is pickled as the storage class
/// torch.<c10::toString(type)>Storage (FloatStorage, BFloat16Storage, ...).
constexpr c10::ScalarType kStorageDtypes[] = {c10::ScalarType::Float, c10::ScalarType::Double,
                                              c10::ScalarType::Half,  c10::ScalarType::BFloat16,
                                              c10::ScalarType::Long,  c10::ScalarType::Int,
                                              c10::ScalarType::Short, c10::ScalarType::Char,
                                              c10::ScalarType::Byte,  c10::ScalarType::Bool};

/// The storage class of `t` without the module: "FloatStorage".
std::string StorageClass(c10::ScalarType t) { return std::string(c10::toString(t)) + "Storage"; }

/// StorageClass of a type a state dict may hold; throws for other types.
std::string StorageName(c10::ScalarType t) {
    if (std::find(std::begin(kStorageDtypes), std::end(kStorageDtypes), t) ==
        std::end(kStorageDtypes)) {
        throw std::runtime_error(std::string("cannot save tensors of type ") + c10::toString(t));
    }
    return StorageClass(t);
}

/// The tensor type of a pickled storage class name ("torch.FloatStorage").
bool StorageDtype(const std::string& global, c10::ScalarType* out) {
    for (const c10::ScalarType t : kStorageDtypes) {
        if (global == "torch." + StorageClass(t)) {
            *out = t;
            return true;
        }
    }
    return false;
}

/// The restricted unpickler. One instance per file; Run() may be called for several
/// consecutive pickles of one stream (the legacy format) and shares the object arena.
class Unpickler {
public:
    Unpickler(const std::string& data, std::string name) : data_(data), name_(std::move(name)) {}

    size_t pos() const { return pos_; }
    void set_pos(size_t p) { pos_ = p; }
    const Obj& at(int id) const { return arena_.at(static_cast<size_t>(id)); }
    /// Storage objects by key (every persistent id seen so far).
    const std::map<std::string, int>& storages() const { return storages_; }

    /// Runs one pickle from pos() to its STOP; returns the top object.
    // Long on purpose: one switch over the opcodes, as pickle's own load loop is written. Each
    // case is a few lines on the shared stack, marks and memo; split up, the cases would only
    // pass that state around.
    int Run() {
        stack_.clear();
        marks_.clear();
        memo_.clear();
        for (;;) {
            const uint8_t op = Byte();
            switch (op) {
                case 0x80:
                    Byte();
                    break;  // PROTO
                case 0x95:
                    Take(8);
                    break;  // FRAME
                case '(':
                    Bound(marks_.size(), "marks");
                    marks_.push_back(stack_.size());
                    break;   // MARK
                case '.': {  // STOP
                    if (stack_.size() != 1 || !marks_.empty()) Bad("malformed pickle (STOP)");
                    return stack_.back();
                }
                case 'N':
                    Push(New(Kind::kNone));
                    break;
                case 0x88:
                case 0x89: {  // NEWTRUE, NEWFALSE
                    const int o = New(Kind::kBool);
                    arena_[o].i = op == 0x88;
                    Push(o);
                    break;
                }
                case 'K':
                    PushInt(Byte());
                    break;  // BININT1
                case 'M':
                    PushInt(static_cast<int64_t>(LittleUnsigned(2)));
                    break;  // BININT2
                case 'J':
                    PushInt(static_cast<int32_t>(LittleUnsigned(4)));
                    break;  // BININT
                case 0x8a:
                    Long(Byte());
                    break;  // LONG1
                case 0x8b:
                    Long(LittleUnsigned(4));
                    break;   // LONG4
                case 'G': {  // BINFLOAT (big-endian)
                    const std::string b = Take(8);
                    uint64_t bits = 0;
                    for (const char c : b) bits = (bits << 8) | static_cast<uint8_t>(c);
                    const int o = New(Kind::kFloat);
                    std::memcpy(&arena_[o].f, &bits, 8);
                    Push(o);
                    break;
                }
                case 'X':
                case 'T':
                    PushStr(Kind::kStr, LittleUnsigned(4));
                    break;
                case 0x8c:
                case 'U':
                    PushStr(Kind::kStr, Byte());
                    break;
                case 'B':
                    PushStr(Kind::kBytes, LittleUnsigned(4));
                    break;
                case 'C':
                    PushStr(Kind::kBytes, Byte());
                    break;
                case 0x8e:
                    PushStr(Kind::kBytes, LittleUnsigned(8));
                    break;  // BINBYTES8
                case ']':
                    Push(New(Kind::kList));
                    break;
                case '}':
                    Push(New(Kind::kDict));
                    break;
                case ')':
                    Push(New(Kind::kTuple));
                    break;
                case 't': {  // TUPLE
                    const int o = New(Kind::kTuple);
                    arena_[o].items = PopToMark();
                    Push(o);
                    break;
                }
                case 0x85:
                case 0x86:
                case 0x87: {  // TUPLE1..3
                    const size_t n = op - 0x84;
                    if (stack_.size() < n + Floor()) Bad("malformed pickle (TUPLE)");
                    const int o = New(Kind::kTuple);
                    arena_[o].items.assign(stack_.end() - static_cast<std::ptrdiff_t>(n),
                                           stack_.end());
                    stack_.resize(stack_.size() - n);
                    Push(o);
                    break;
                }
                case 'q':
                    Put(Byte());
                    break;  // BINPUT
                case 'r':
                    Put(LittleUnsigned(4));
                    break;  // LONG_BINPUT
                case 0x94:
                    Put(memo_.size());
                    break;  // MEMOIZE
                case 'h':
                    Push(Memo(Byte()));
                    break;  // BINGET
                case 'j':
                    Push(Memo(LittleUnsigned(4)));
                    break;   // LONG_BINGET
                case 'c': {  // GLOBAL
                    const std::string module = Line();
                    const std::string gname = Line();
                    Push(Global(module + "." + gname));
                    break;
                }
                case 0x93: {  // STACK_GLOBAL
                    const int gname = Pop();
                    const int module = Pop();
                    if (at(module).kind != Kind::kStr || at(gname).kind != Kind::kStr) {
                        Bad("malformed pickle (STACK_GLOBAL)");
                    }
                    Push(Global(at(module).s + "." + at(gname).s));
                    break;
                }
                case 'a': {  // APPEND
                    const int v = Pop();
                    List(Top()).items.push_back(v);
                    break;
                }
                case 'e': {  // APPENDS
                    std::vector<int> v = PopToMark();
                    auto& l = List(Top()).items;
                    l.insert(l.end(), v.begin(), v.end());
                    break;
                }
                case 's': {  // SETITEM
                    const int v = Pop();
                    const int k = Pop();
                    SetItem(Top(), k, v);
                    break;
                }
                case 'u': {  // SETITEMS
                    std::vector<int> kv = PopToMark();
                    if (kv.size() % 2 != 0) Bad("malformed pickle (SETITEMS)");
                    const int d = Top();
                    for (size_t j = 0; j < kv.size(); j += 2) SetItem(d, kv[j], kv[j + 1]);
                    break;
                }
                case 'R': {  // REDUCE
                    const int args = Pop();
                    const int fn = Pop();
                    Push(Reduce(fn, args));
                    break;
                }
                case 'b': {  // BUILD
                    Pop();   // state: only OrderedDict's _metadata, which a state dict may carry
                    const int o = Top();
                    if (at(o).kind != Kind::kDict && at(o).kind != Kind::kTensor &&
                        at(o).kind != Kind::kNumpyDtype) {
                        Bad("pickle sets the state of an object other than a dict, tensor or "
                            "numpy dtype");
                    }
                    break;
                }
                case 'Q':
                    Push(PersistentLoad(Pop()));
                    break;  // BINPERSID
                default: {
                    std::ostringstream os;
                    os << "unsupported or corrupt pickle opcode 0x" << std::hex << int(op)
                       << " at byte " << std::dec << pos_ - 1;
                    Bad(os.str());
                }
            }
        }
    }

    [[noreturn]] void Bad(const std::string& what) const {
        Fail(name_, what + " (not a torch.save state dict, or a corrupt/truncated one)");
    }

private:
    uint8_t Byte() {
        if (pos_ >= data_.size()) Bad("file ends inside a pickle");
        return static_cast<uint8_t>(data_[pos_++]);
    }
    std::string Take(uint64_t n) {
        if (n > data_.size() - pos_) Bad("file ends inside a pickle");
        std::string s = data_.substr(pos_, n);
        pos_ += n;
        return s;
    }
    uint64_t LittleUnsigned(int n) {
        const std::string b = Take(n);
        uint64_t v = 0;
        for (int j = n - 1; j >= 0; --j) v = (v << 8) | static_cast<uint8_t>(b[j]);
        return v;
    }
    std::string Line() {
        // Looked for in the next 257 bytes only: a search to the end per opcode was quadratic.
        const size_t end = data_.substr(pos_, 257).find('\n');
        if (end == std::string::npos) Bad("malformed GLOBAL in pickle");
        std::string s = data_.substr(pos_, end);
        pos_ += end + 1;
        return s;
    }
    /// Refuses the pickle when a structure of `count` entries would grow past
    /// kMaxPickleObjects: its memory is then bounded whatever the file holds.
    void Bound(size_t count, const char* what) const {
        if (count >= kMaxPickleObjects) {
            Bad("pickle makes more than " + std::to_string(kMaxPickleObjects) + " " + what +
                ", more than a state dict of 40,000 tensors");
        }
    }
    void Put(uint64_t key) {
        const int o = Top();
        if (memo_.count(key) == 0) Bound(memo_.size(), "memo entries");
        memo_[key] = o;
    }
    int New(Kind k) {
        // Every opcode makes at most one object and consumes at least one byte.
        Bound(arena_.size(), "objects");
        arena_.emplace_back();
        arena_.back().kind = k;
        return static_cast<int>(arena_.size() - 1);
    }
    void Push(int o) {
        Bound(stack_.size(), "stack entries");
        stack_.push_back(o);
    }
    size_t Floor() const { return marks_.empty() ? 0 : marks_.back(); }
    int Pop() {
        if (stack_.size() <= Floor()) Bad("malformed pickle (stack underflow)");
        const int o = stack_.back();
        stack_.pop_back();
        return o;
    }
    int Top() const {
        if (stack_.size() <= Floor()) Bad("malformed pickle (stack underflow)");
        return stack_.back();
    }
    std::vector<int> PopToMark() {
        if (marks_.empty()) Bad("malformed pickle (no MARK)");
        const size_t m = marks_.back();
        marks_.pop_back();
        std::vector<int> out(stack_.begin() + static_cast<std::ptrdiff_t>(m), stack_.end());
        stack_.resize(m);
        return out;
    }
    int Memo(uint64_t key) const {
        const auto it = memo_.find(key);
        if (it == memo_.end()) Bad("malformed pickle (unknown memo entry)");
        return it->second;
    }
    Obj& List(int o) {
        if (arena_[o].kind != Kind::kList) Bad("pickle appends to a non-list");
        return arena_[o];
    }
    void SetItem(int d, int k, int v) {
        if (arena_[d].kind != Kind::kDict) Bad("pickle sets an item of a non-dict");
        arena_[d].items.push_back(k);
        arena_[d].items.push_back(v);
    }
    void PushInt(int64_t v) {
        const int o = New(Kind::kInt);
        arena_[o].i = v;
        Push(o);
    }
    void PushStr(Kind k, uint64_t n) {
        std::string s = Take(n);
        const int o = New(k);
        arena_[o].s = std::move(s);
        Push(o);
    }
    void Long(uint64_t n) {
        const std::string b = Take(n);
        if (n > 8) {  // only torch's legacy magic number is this big
            const int o = New(Kind::kBigInt);
            arena_[o].s = b;
            Push(o);
            return;
        }
        uint64_t v = 0;
        for (size_t j = n; j-- > 0;) v = (v << 8) | static_cast<uint8_t>(b[j]);
        if (n > 0 && n < 8 && (static_cast<uint8_t>(b[n - 1]) & 0x80)) v -= uint64_t{1} << (8 * n);
        PushInt(static_cast<int64_t>(v));
    }
    int Global(const std::string& g) {
        c10::ScalarType t;
        if (StorageDtype(g, &t)) {
            const int o = New(Kind::kStorageType);
            arena_[o].dtype = t;
            return o;
        }
        if (g == "collections.OrderedDict" || g == "torch._utils._rebuild_tensor_v2" ||
            g == "torch._utils._rebuild_tensor" || g == "torch._utils._rebuild_parameter" ||
            IsNumpyScalarGlobal(g)) {
            const int o = New(Kind::kGlobal);
            arena_[o].s = g;
            return o;
        }
        Bad("pickle refers to " + g + ", which a plain state dict of tensors does not contain");
    }
    std::vector<int64_t> IntTuple(int o, const char* what) const {
        if (at(o).kind != Kind::kTuple) Bad(std::string("tensor ") + what + " is not a tuple");
        // Checked before the copy: a long tuple in the memo, passed to a million calls, made
        // the reading quadratic.
        if (at(o).items.size() > kMaxDims) {
            Bad(std::string("tensor ") + what + " has " + std::to_string(at(o).items.size()) +
                " dimensions, more than " + std::to_string(kMaxDims));
        }
        std::vector<int64_t> v;
        for (const int x : at(o).items) {
            if (at(x).kind != Kind::kInt || at(x).i < 0) {
                Bad(std::string("tensor ") + what + " holds a non-integer or negative entry");
            }
            v.push_back(at(x).i);
        }
        return v;
    }
    /// The globals a training checkpoint's numpy scalar (e.g. {"best_result": np.float64})
    /// pickles: numpy's scalar and dtype constructors, and _codecs.encode, which protocol 2
    /// uses for the scalar's bytes. None of them runs: the reader builds inert objects.
    static bool IsNumpyScalarGlobal(const std::string& g) {
        return g == "numpy.core.multiarray.scalar" || g == "numpy._core.multiarray.scalar" ||
               g == "numpy.dtype" || g == "_codecs.encode";
    }
    /// numpy.dtype(str, False, True) -> kNumpyDtype; _codecs.encode(str, "latin1") -> kBytes;
    /// scalar(dtype, bytes) -> kNumpyScalar (kept, never converted: no state dict holds one).
    int NumpyScalarPart(const std::string& g, const std::vector<int>& a) {
        const auto is = [&](size_t j, Kind k) { return j < a.size() && at(a[j]).kind == k; };
        if (g == "numpy.dtype") {
            if (a.size() != 3 || !is(0, Kind::kStr) || at(a[0]).s.size() > 16) {
                Bad("numpy.dtype with unexpected arguments");
            }
            const int o = New(Kind::kNumpyDtype);
            arena_[o].s = at(a[0]).s;
            return o;
        }
        if (g == "_codecs.encode") {
            if (a.size() != 2 || !is(0, Kind::kStr) || !is(1, Kind::kStr) ||
                at(a[1]).s != "latin1") {
                Bad("_codecs.encode other than of a string to latin1");
            }
            const int o = New(Kind::kBytes);
            arena_[o].s = Latin1(at(a[0]).s);
            return o;
        }
        if (a.size() != 2 || !is(0, Kind::kNumpyDtype) || !is(1, Kind::kBytes)) {
            Bad(g + " with arguments other than a numpy dtype and bytes");
        }
        const int o = New(Kind::kNumpyScalar);
        arena_[o].s = at(a[1]).s;
        return o;
    }
    /// The latin-1 bytes of the UTF-8 string `utf8` (code points below 256 only).
    std::string Latin1(const std::string& utf8) const {
        std::string out;
        for (size_t j = 0; j < utf8.size(); ++j) {
            const auto c = static_cast<uint8_t>(utf8[j]);
            if (c < 0x80) {
                out.push_back(static_cast<char>(c));
            } else if ((c == 0xc2 || c == 0xc3) && j + 1 < utf8.size() &&
                       (static_cast<uint8_t>(utf8[j + 1]) & 0xc0) == 0x80) {
                out.push_back(static_cast<char>(((c & 0x03) << 6) |
                                                (static_cast<uint8_t>(utf8[j + 1]) & 0x3f)));
                ++j;
            } else {
                Bad("_codecs.encode of a string that is not latin-1");
            }
        }
        return out;
    }
    int Reduce(int fn, int args) {
        if (at(fn).kind != Kind::kGlobal || at(args).kind != Kind::kTuple) {
            Bad("pickle calls something other than a known global");
        }
        const std::string g = at(fn).s;
        // No global a state dict uses takes more than 7 arguments; refused before the copy (a
        // million calls with a long tuple from the memo were quadratic).
        if (at(args).items.size() > 8) {
            Bad(g + " called with " + std::to_string(at(args).items.size()) + " arguments");
        }
        const std::vector<int> a = at(args).items;
        if (g == "collections.OrderedDict") {
            if (!a.empty()) Bad("OrderedDict built from arguments");
            return New(Kind::kDict);
        }
        if (IsNumpyScalarGlobal(g)) return NumpyScalarPart(g, a);
        if (g == "torch._utils._rebuild_parameter") {
            if (a.empty() || at(a[0]).kind != Kind::kTensor)
                Bad("_rebuild_parameter of a non-tensor");
            return a[0];
        }
        // _rebuild_tensor(storage, offset, size, stride) and _rebuild_tensor_v2(..., requires_grad,
        // backward_hooks[, metadata]).
        if (a.size() < 4 || at(a[0]).kind != Kind::kStorage || at(a[1]).kind != Kind::kInt) {
            Bad(g + " with unexpected arguments");
        }
        const int o = New(Kind::kTensor);
        Obj t;
        t.kind = Kind::kTensor;
        t.storage = a[0];
        t.i = at(a[1]).i;
        t.dtype = at(a[0]).dtype;
        t.sizes = IntTuple(a[2], "size");
        t.strides = IntTuple(a[3], "stride");
        if (t.sizes.size() != t.strides.size() || t.i < 0) {
            Bad(g + ": size and stride of different lengths, or a negative offset");
        }
        arena_[o] = std::move(t);
        return o;
    }
    int PersistentLoad(int pid) {
        // ('storage', storage_type, key, location, numel[, view_metadata])
        const Obj& p = at(pid);
        if (p.kind != Kind::kTuple || p.items.size() < 5 || p.items.size() > 6 ||
            at(p.items[0]).kind != Kind::kStr || at(p.items[0]).s != "storage" ||
            at(p.items[1]).kind != Kind::kStorageType || at(p.items[2]).kind != Kind::kStr ||
            at(p.items[3]).kind != Kind::kStr || at(p.items[4]).kind != Kind::kInt ||
            at(p.items[4]).i < 0) {
            Bad("persistent id is not a tensor storage");
        }
        if (p.items.size() == 6 && at(p.items[5]).kind != Kind::kNone) {
            Bad("storage views (PyTorch < 0.4 files) are not supported");
        }
        const std::string key = at(p.items[2]).s;
        const c10::ScalarType dtype = at(p.items[1]).dtype;
        const int64_t numel = at(p.items[4]).i;
        const auto it = storages_.find(key);
        if (it != storages_.end()) {
            if (at(it->second).dtype != dtype || at(it->second).i != numel) {
                Bad("storage " + key + " declared twice with different types or sizes");
            }
            return it->second;
        }
        const int o = New(Kind::kStorage);
        arena_[o].s = key;
        arena_[o].dtype = dtype;
        arena_[o].i = numel;
        storages_[key] = o;
        return o;
    }

    const std::string& data_;
    std::string name_;
    size_t pos_ = 0;
    std::vector<Obj> arena_;
    std::vector<int> stack_;
    std::vector<size_t> marks_;
    std::map<uint64_t, int> memo_;
    std::map<std::string, int> storages_;
};

/// The state dict inside the top object: a dict of str -> tensor, or one such dict under a
/// "state_dict" / "model" / "model_state_dict" / "net" key of a wrapper dict.
int FindStateDict(const Unpickler& u, int top, const std::string& name, std::string* wrapper) {
    const auto is_state_dict = [&](int o) {
        if (u.at(o).kind != Kind::kDict || u.at(o).items.empty()) return false;
        for (size_t j = 0; j < u.at(o).items.size(); j += 2) {
            if (u.at(u.at(o).items[j]).kind != Kind::kStr ||
                u.at(u.at(o).items[j + 1]).kind != Kind::kTensor) {
                return false;
            }
        }
        return true;
    };
    if (is_state_dict(top)) return top;
    if (u.at(top).kind == Kind::kDict) {
        for (const char* k : {"state_dict", "model", "model_state_dict", "net"}) {
            for (size_t j = 0; j < u.at(top).items.size(); j += 2) {
                const Obj& key = u.at(u.at(top).items[j]);
                if (key.kind == Kind::kStr && key.s == k && is_state_dict(u.at(top).items[j + 1])) {
                    *wrapper = k;
                    return u.at(top).items[j + 1];
                }
            }
        }
    }
    Fail(name, "holds no state dict (a dict of parameter names to tensors)");
}

/// Bytes of the storage object `o` (its elements times their size), refused beyond the budget.
uint64_t StorageBytes(const Unpickler& u, int o, const std::string& name) {
    const Obj& st = u.at(o);
    const uint64_t element = c10::elementSize(st.dtype);
    const auto numel = static_cast<uint64_t>(st.i);
    if (numel > kMaxTorchSaveBytes / element) {
        Fail(name, "storage " + st.s + " declares " + std::to_string(numel) + " elements of " +
                       std::to_string(element) + " bytes, more than the " +
                       std::to_string(kMaxTorchSaveBytes) + " a checkpoint may hold");
    }
    return numel * element;
}

/// Tensors of the state dict `sd`: views of `storages` (flat tensors by key), copied out. Every
/// view is checked against its storage (within it, no more elements than it has), and the
/// views' bytes in all against kMaxTorchSaveBytes, before the first is copied.
StateDict BuildTensors(const Unpickler& u, int sd,
                       const std::map<std::string, torch::Tensor>& storages,
                       const std::string& name) {
    const auto& items = u.at(sd).items;
    std::set<std::string> seen;
    uint64_t total = 0;
    for (size_t j = 0; j < items.size(); j += 2) {
        const std::string& key = u.at(items[j]).s;
        if (!seen.insert(key).second) Fail(name, "tensor " + key + " appears twice");
        const Obj& t = u.at(items[j + 1]);
        const Obj& st = u.at(t.storage);
        if (storages.count(st.s) == 0) Fail(name, "storage of tensor " + key + " is missing");
        const int64_t numel = st.i;
        // Largest element index the view touches, overflow-checked.
        int64_t last = t.i;
        bool empty = false;
        for (size_t d = 0; d < t.sizes.size(); ++d) {
            if (t.sizes[d] == 0) empty = true;
            if (t.sizes[d] > 0) {
                if (t.strides[d] != 0 &&
                    t.sizes[d] - 1 > (std::numeric_limits<int64_t>::max() - last) / t.strides[d]) {
                    Fail(name, "tensor " + key + " has an impossible shape");
                }
                last += (t.sizes[d] - 1) * t.strides[d];
            }
        }
        if (!empty && last >= numel) {
            Fail(name, "tensor " + key + " reaches past the end of its storage (element " +
                           std::to_string(last) + " of " + std::to_string(numel) + ")");
        }
        const uint64_t element = c10::elementSize(st.dtype);
        uint64_t count = 1;
        for (const int64_t s : t.sizes) {
            if (s > 0 && count > kMaxTorchSaveBytes / element / static_cast<uint64_t>(s)) {
                Fail(name, "tensor " + key + " declares more than the " +
                               std::to_string(kMaxTorchSaveBytes) + " bytes a checkpoint may hold");
            }
            count *= static_cast<uint64_t>(s);
        }
        // A state dict's tensors are views within their storages; one with more elements than
        // its storage (stride 0, as expand() makes) would let a few bytes of file ask for the
        // whole budget.
        if (!empty && count > static_cast<uint64_t>(numel)) {
            Fail(name, "tensor " + key + " has " + std::to_string(count) +
                           " elements, more than the " + std::to_string(numel) +
                           " of its storage (a view that repeats elements)");
        }
        total += empty ? 0 : count * element;
        if (total > kMaxTorchSaveBytes) {
            Fail(name, "its tensors take more than the " + std::to_string(kMaxTorchSaveBytes) +
                           " bytes a checkpoint may hold (tensor " + key + " passes it)");
        }
    }
    StateDict out;
    for (size_t j = 0; j < items.size(); j += 2) {
        const Obj& t = u.at(items[j + 1]);
        const torch::Tensor& storage = storages.at(u.at(t.storage).s);
        const bool empty = std::find(t.sizes.begin(), t.sizes.end(), 0) != t.sizes.end();
        torch::Tensor v = empty ? torch::empty(t.sizes, storage.options())
                                : storage.as_strided(t.sizes, t.strides, t.i).clone();
        out.emplace_back(u.at(items[j]).s, v.contiguous());
    }
    return out;
}

// Long on purpose: one checked sequence (directory, pickle, every storage's declared size
// against its record and the budget, then the records), each step using the previous one's.
TorchSaveContents ReadZip(const std::shared_ptr<caffe2::serialize::ReadAdapterInterface>& in,
                          const std::string& name) {
    std::string first;
    const std::map<std::string, ZipEntry> entries = ReadZipDirectory(*in, name, &first);
    const std::string folder = first.substr(0, first.find('/'));  // as LibTorch's reader takes it
    try {
        caffe2::serialize::PyTorchStreamReader reader(in);
        if (reader.hasRecord("constants.pkl") || reader.hasRecord("code/__torch__.py")) {
            Fail(name, "is a TorchScript archive (torch.jit.save), not a torch.save state dict");
        }
        if (!reader.hasRecord("data.pkl"))
            Fail(name, "zip archive without data.pkl: not a torch.save file");
        auto [pickle_ptr, pickle_size] = reader.getRecord("data.pkl");  // checked: <= 64 MiB
        const std::string pickle(static_cast<const char*>(pickle_ptr.get()), pickle_size);
        pickle_ptr.clear();
        Unpickler u(pickle, name);
        const int top = u.Run();
        // Every storage's declared size against its record and, in all, the budget, before any
        // is read: a 1 MB zip of deflated records expanded to 2-3 GB before any check.
        uint64_t total = 0;
        for (const auto& [key, obj] : u.storages()) {
            const uint64_t bytes = StorageBytes(u, obj, name);
            const auto it = entries.find(folder + "/data/" + key);
            if (it == entries.end()) Fail(name, "storage record data/" + key + " is missing");
            if (it->second.size != bytes) {
                Fail(name, "storage " + key + " declares " + std::to_string(bytes) + " bytes (" +
                               std::to_string(u.at(obj).i) + " elements), its record " +
                               it->first + " holds " + std::to_string(it->second.size));
            }
            total += bytes;
            if (total > kMaxTorchSaveBytes) {
                Fail(name, "its storages declare more than the " +
                               std::to_string(kMaxTorchSaveBytes) +
                               " bytes a checkpoint may hold (storage " + key + " passes it)");
            }
        }
        std::map<std::string, torch::Tensor> storages;
        for (const auto& [key, obj] : u.storages()) {
            const Obj& st = u.at(obj);
            const auto opts = torch::TensorOptions().dtype(st.dtype);
            if (st.i == 0) {
                storages[key] = torch::empty({0}, opts);
                continue;
            }
            // Inflating writes into the declared size and stops there (miniz's
            // extract_to_mem); the record's bytes become the storage without a copy.
            auto holder =
                std::make_shared<at::DataPtr>(std::get<0>(reader.getRecord("data/" + key)));
            storages[key] = torch::from_blob(holder->get(), {st.i}, [holder](void*) {}, opts);
        }
        TorchSaveContents out;
        out.format = "zip";
        const int sd = FindStateDict(u, top, name, &out.wrapper);
        out.tensors = BuildTensors(u, sd, storages, name);
        return out;
    } catch (const c10::Error& e) {
        Fail(name, std::string("corrupt zip archive: ") + e.what_without_backtrace());
    }
}

TorchSaveContents ReadLegacy(const std::string& bytes, const std::string& name) {
    Unpickler u(bytes, name);
    const int magic = u.Run();
    // 0x1950a86a20f9469cfc6c, little-endian.
    static const std::string kMagic("\x6c\xfc\x9c\x46\xf9\x20\x6a\xa8\x50\x19", 10);
    if (u.at(magic).kind != Kind::kBigInt || u.at(magic).s != kMagic) {
        Fail(name, "is a pickle but not a torch.save file (no magic number)");
    }
    const int protocol = u.Run();
    if (u.at(protocol).kind != Kind::kInt || u.at(protocol).i != 1001) {
        Fail(name, "unsupported torch.save legacy protocol version");
    }
    const int sys_info = u.Run();
    if (u.at(sys_info).kind != Kind::kDict) Fail(name, "malformed sys_info in torch.save header");
    const auto& si = u.at(sys_info).items;
    for (size_t j = 0; j < si.size(); j += 2) {
        if (u.at(si[j]).kind == Kind::kStr && u.at(si[j]).s == "little_endian" &&
            u.at(si[j + 1]).kind == Kind::kBool && u.at(si[j + 1]).i == 0) {
            Fail(name, "was saved on a big-endian machine, which is not supported");
        }
    }
    const int top = u.Run();
    const int keys = u.Run();
    if (u.at(keys).kind != Kind::kList) Fail(name, "malformed storage key list");
    std::map<std::string, torch::Tensor> storages;
    size_t pos = u.pos();
    for (const int k : u.at(keys).items) {
        if (u.at(k).kind != Kind::kStr) Fail(name, "malformed storage key list");
        const auto it = u.storages().find(u.at(k).s);
        if (it == u.storages().end()) Fail(name, "storage " + u.at(k).s + " is not referenced");
        if (storages.count(u.at(k).s)) Fail(name, "storage " + u.at(k).s + " listed twice");
        if (bytes.size() - pos < 8) Fail(name, "file ends before storage " + u.at(k).s);
        int64_t numel = 0;
        std::memcpy(&numel, bytes.data() + pos, 8);
        pos += 8;
        const int64_t declared = u.at(it->second).i;
        if (numel != declared) {
            Fail(name, "storage " + u.at(k).s + " holds " + std::to_string(numel) +
                           " elements, its tensors declare " + std::to_string(declared));
        }
        // Within the file, which is within the budget: checked before it is allocated.
        const uint64_t size = StorageBytes(u, it->second, name);
        if (size > bytes.size() - pos) Fail(name, "file ends inside storage " + u.at(k).s);
        torch::Tensor s =
            torch::empty({numel}, torch::TensorOptions().dtype(u.at(it->second).dtype));
        if (size > 0) std::memcpy(s.data_ptr(), bytes.data() + pos, size);
        storages[u.at(k).s] = s;
        pos += size;
    }
    TorchSaveContents out;
    out.format = "legacy";
    const int sd = FindStateDict(u, top, name, &out.wrapper);
    out.tensors = BuildTensors(u, sd, storages, name);
    return out;
}

// ------------------------------------------------------------------------ pickle writer

class PickleWriter {
public:
    void Op(uint8_t op) { out_ += static_cast<char>(op); }
    void Str(const std::string& s) {
        Op('X');
        Le(s.size(), 4);
        out_ += s;
    }
    void Int(int64_t v) {
        if (v >= 0 && v < 256) {
            Op('K');
            Le(static_cast<uint64_t>(v), 1);
        } else if (v >= std::numeric_limits<int32_t>::min() &&
                   v <= std::numeric_limits<int32_t>::max()) {
            Op('J');
            Le(static_cast<uint32_t>(static_cast<int32_t>(v)), 4);
        } else {
            Op(0x8a);
            Op(8);
            Le(static_cast<uint64_t>(v), 8);
        }
    }
    void Global(const std::string& module, const std::string& name) {
        Op('c');
        out_ += module + "\n" + name + "\n";
    }
    void IntTuple(c10::IntArrayRef v) {
        Op('(');
        for (const int64_t x : v) Int(x);
        Op('t');
    }
    std::string& bytes() { return out_; }

private:
    void Le(uint64_t v, int n) {
        for (int j = 0; j < n; ++j) out_ += static_cast<char>((v >> (8 * j)) & 0xff);
    }
    std::string out_;
};

/// Reads the torch.save file behind `in` (a zip lazily, a legacy stream whole).
TorchSaveContents ReadFrom(const std::shared_ptr<caffe2::serialize::ReadAdapterInterface>& in,
                           const std::string& name) {
    const std::string head = ReadAt(*in, 0, std::min<uint64_t>(in->size(), 262));
    try {
        if (head.size() >= 4 && head.compare(0, 4, "PK\x03\x04") == 0) return ReadZip(in, name);
        if (!head.empty() && static_cast<uint8_t>(head[0]) == 0x80)
            return ReadLegacy(ReadAt(*in, 0, in->size()), name);
    } catch (const std::bad_alloc&) {
        Fail(name, "declares more data than fits in memory (corrupt file)");
    } catch (const c10::Error& e) {
        Fail(name, std::string("corrupt file: ") + e.what_without_backtrace());
    } catch (const std::logic_error& e) {
        // LibTorch's zip reader parses the version record with std::stoull: a huge or
        // non-numeric one ended as "regbench: error: stoull", without the file.
        Fail(name, std::string("corrupt file (") + e.what() + " on one of its records)");
    }
    if (head.size() >= 262 && head.compare(257, 5, "ustar") == 0) {
        Fail(name, "is a tar archive (torch.save of PyTorch < 0.4), which is not supported");
    }
    Fail(name, head.empty() ? "is empty" : "is neither a zip-format nor a legacy torch.save file");
}

/// `path` opened once, without blocking, and checked as opened: a check by name and a later
/// open let a symbolic link flipped to a FIFO in between block for ever.
struct OpenedFile {
    explicit OpenedFile(const std::string& path) {
        fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
        if (fd < 0) {
            if (errno == ENOENT) Fail(path, "no such file");
            Fail(path, std::string("cannot be opened: ") + std::strerror(errno));
        }
        if (::fstat(fd, &st) != 0) {
            const int err = errno;
            ::close(fd);
            Fail(path, std::string("cannot be read: ") + std::strerror(err));
        }
        std::string problem;
        if (S_ISDIR(st.st_mode)) {
            problem = "is a directory, not a file";
        } else if (!S_ISREG(st.st_mode)) {
            problem = "not a regular file (a FIFO, socket or device); regbench reads inputs from "
                      "regular files only";
        } else if (static_cast<uint64_t>(st.st_size) > kMaxTorchSaveBytes) {
            // A 30 GB sparse file with a zip header was read into memory until the OOM killer.
            problem = "is " + std::to_string(st.st_size) + " bytes, more than the " +
                      std::to_string(kMaxTorchSaveBytes) +
                      " a checkpoint regbench reads may have (the largest authors' file is under "
                      "100 MB)";
        }
        if (!problem.empty()) {
            ::close(fd);
            Fail(path, problem);
        }
    }
    ~OpenedFile() { ::close(fd); }
    OpenedFile(const OpenedFile&) = delete;
    OpenedFile& operator=(const OpenedFile&) = delete;
    int fd = -1;
    struct stat st {};
};

}  // namespace

TorchSaveContents ReadTorchSaveBytes(const std::string& bytes, const std::string& name) {
    return ReadFrom(
        std::make_shared<caffe2::serialize::MemoryReadAdapter>(bytes.data(), bytes.size()), name);
}

TorchSaveContents ReadTorchSaveFile(const std::string& path) {
    const OpenedFile f(path);
    // The hash, streamed through the opened file to its end (a /proc file reports size 0).
    Sha256 hash;
    uint64_t size = 0;
    std::vector<char> buf(1 << 20);
    for (;;) {
        const ssize_t n = ::read(f.fd, buf.data(), buf.size());
        if (n == 0) break;
        if (n < 0) {
            if (errno == EINTR) continue;
            // An EIO (/proc/self/mem) ended as a bare "basic_filebuf::underflow".
            Fail(path, std::string("read error: ") + std::strerror(errno));
        }
        hash.Update(buf.data(), static_cast<size_t>(n));
        size += static_cast<uint64_t>(n);
        if (size > static_cast<uint64_t>(f.st.st_size)) break;
    }
    const auto changed = [&] {
        struct stat now {};
        return size != static_cast<uint64_t>(f.st.st_size) || ::fstat(f.fd, &now) != 0 ||
               now.st_size != f.st.st_size || now.st_mtim.tv_sec != f.st.st_mtim.tv_sec ||
               now.st_mtim.tv_nsec != f.st.st_mtim.tv_nsec;
    };
    if (changed()) Fail(path, "changed while it was read; read it again when it is complete");
    TorchSaveContents contents =
        ReadFrom(std::make_shared<FdReadAdapter>(f.fd, size, path), path);
    // The hash is of the bytes read only if the file did not change in between.
    if (changed()) Fail(path, "changed while it was read; read it again when it is complete");
    contents.sha256 = hash.Hex();
    contents.bytes = size;
    return contents;
}

void CheckTorchZipSizes(const std::string& path) {
    const OpenedFile f(path);
    const FdReadAdapter in(f.fd, static_cast<uint64_t>(f.st.st_size), path);
    if (in.size() < 4 || ReadAt(in, 0, 4) != "PK\x03\x04") return;  // LibTorch names the rest
    std::string first;
    uint64_t total = 0;
    for (const auto& [name, e] : ReadZipDirectory(in, path, &first)) {
        total += e.size;  // each <= kMaxTorchSaveBytes: no overflow
        if (total > kMaxTorchSaveBytes) {
            Fail(path, "its records declare more than the " + std::to_string(kMaxTorchSaveBytes) +
                           " bytes a checkpoint may hold (record " + name + " passes it)");
        }
    }
}

std::string WriteTorchSaveZip(const StateDict& tensors) {
    PickleWriter p;
    p.Op(0x80);
    p.Op(2);
    p.Global("collections", "OrderedDict");
    p.Op(')');
    p.Op('R');
    p.Op('(');
    std::vector<torch::Tensor> storages;
    for (size_t j = 0; j < tensors.size(); ++j) {
        const torch::Tensor t = tensors[j].second.detach().to(torch::kCPU).contiguous();
        storages.push_back(t);
        p.Str(tensors[j].first);
        p.Global("torch._utils", "_rebuild_tensor_v2");
        p.Op('(');
        p.Op('(');  // persistent id
        p.Str("storage");
        p.Global("torch", StorageName(t.scalar_type()));
        p.Str(std::to_string(j));
        p.Str("cpu");
        p.Int(t.numel());
        p.Op('t');
        p.Op('Q');
        p.Int(0);
        p.IntTuple(t.sizes());
        p.IntTuple(t.strides());
        p.Op(0x89);  // requires_grad False
        p.Global("collections", "OrderedDict");
        p.Op(')');
        p.Op('R');
        p.Op('t');
        p.Op('R');
    }
    p.Op('u');
    p.Op('.');
    std::string out;
    {
        caffe2::serialize::PyTorchStreamWriter writer([&](const void* buf, size_t n) -> size_t {
            out.append(static_cast<const char*>(buf), n);
            return n;
        });
        writer.writeRecord("data.pkl", p.bytes().data(), p.bytes().size());
        for (size_t j = 0; j < storages.size(); ++j) {
            writer.writeRecord("data/" + std::to_string(j), storages[j].data_ptr(),
                               storages[j].numel() * storages[j].element_size());
        }
        writer.writeEndOfFile();
    }
    return out;
}

}  // namespace regbench::networks
