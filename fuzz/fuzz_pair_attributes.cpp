// libFuzzer target: the pair file's string attributes (provenance, and pair 0's shape, category
// and meta), which the HDF5 reader parses as UTF-8 text and depth-limited JSON. Each input is
// cut at the byte 0x01 into up to four values written (raw bytes) over those attributes of a
// valid one-pair file (fuzz/corpus/pair_file/one_pair.h5); ReadPairFile then reads it. Every
// std::exception is a refusal; a crash, sanitizer report or other exception is a finding.
#include <hdf5.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz/fuzz_input.hpp"
#include "protocols/pair_file.hpp"

namespace {

std::string BaseFile() {
    std::ifstream in(REGBENCH_FUZZ_BASE_PAIR_FILE, std::ios::binary);
    if (!in) std::abort();
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void PutStringAttr(hid_t obj, const char* name, const std::string& v) {
    if (H5Aexists(obj, name) > 0) H5Adelete(obj, name);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, v.empty() ? 1 : v.size());
    H5Tset_strpad(type, H5T_STR_NULLPAD);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
    const std::string bytes = v.empty() ? std::string(1, '\0') : v;
    if (attr < 0 || H5Awrite(attr, type, bytes.data()) < 0) std::abort();
    H5Aclose(attr);
    H5Sclose(space);
    H5Tclose(type);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::string base = BaseFile();
    std::vector<std::string> parts(1);
    for (std::size_t i = 0; i < size; ++i) {
        if (data[i] == 0x01 && parts.size() < 4) {
            parts.emplace_back();
        } else {
            parts.back().push_back(static_cast<char>(data[i]));
        }
    }
    const std::string path = regbench::fuzz::WriteInput(
        reinterpret_cast<const std::uint8_t*>(base.data()), base.size(), "_attrs.h5");
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    if (file < 0) std::abort();
    PutStringAttr(file, "provenance", parts[0]);
    const hid_t group = H5Gopen2(file, "/pairs/000000", H5P_DEFAULT);
    if (group < 0) std::abort();
    const char* names[] = {"shape", "category", "meta"};
    for (std::size_t k = 1; k < parts.size(); ++k) PutStringAttr(group, names[k - 1], parts[k]);
    H5Gclose(group);
    H5Fclose(file);
    try {
        (void)regbench::ReadPairFile(path);
    } catch (const std::exception&) {
    }
    ::unlink(path.c_str());
    return 0;
}
