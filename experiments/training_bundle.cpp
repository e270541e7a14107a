#include "experiments/training_bundle.hpp"

#include <fstream>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "core/atomic_file.hpp"
#include "core/input_file.hpp"
#include "core/pair_normalization.hpp"

namespace regbench {
namespace {

constexpr const char* kFormat = "regbench-training-bundle";
constexpr int kFormatVersion = 1;

/// Row-major n x 3 data as one flat array.
template <typename Matrix>
nlohmann::json Flat(const Matrix& m) {
    using Scalar = typename Matrix::Scalar;
    return std::vector<Scalar>(m.data(), m.data() + m.size());
}

template <typename Matrix>
Matrix Rows3(const nlohmann::json& flat, const std::string& what) {
    using Scalar = typename Matrix::Scalar;
    const auto v = flat.get<std::vector<Scalar>>();
    if (v.size() % 3 != 0) {
        throw std::invalid_argument(what + " holds " + std::to_string(v.size()) +
                                    " numbers, not rows of 3");
    }
    Matrix m(static_cast<Eigen::Index>(v.size() / 3), 3);
    std::copy(v.begin(), v.end(), m.data());
    return m;
}

nlohmann::json ShapeToJson(const ShapeSource& s) {
    nlohmann::json j = {{"name", s.name()}, {"category", s.category()}};
    if (s.has_stored_pair()) {
        throw std::invalid_argument("training bundle: shape '" + s.name() +
                                    "' is a stored pair; bundles carry meshes and point clouds");
    }
    if (const Mesh* mesh = s.mesh()) {
        j["vertices"] = Flat(mesh->vertices);
        j["faces"] = Flat(mesh->faces);
    } else {
        j["points"] = Flat(*s.points());
    }
    return j;
}

ShapeSource ShapeFromJson(const nlohmann::json& j) {
    auto name = j.at("name").get<std::string>();
    auto category = j.at("category").get<std::string>();
    if (j.contains("points")) {
        return ShapeSource::FromPoints(Rows3<PointCloud>(j.at("points"), "shape '" + name + "'"),
                                       std::move(name), std::move(category));
    }
    Mesh mesh;
    mesh.vertices = Rows3<decltype(mesh.vertices)>(j.at("vertices"), "shape '" + name + "'");
    mesh.faces = Rows3<decltype(mesh.faces)>(j.at("faces"), "shape '" + name + "' faces");
    return ShapeSource::FromMesh(std::move(mesh), std::move(name), std::move(category));
}

nlohmann::json ShapesToJson(const std::vector<ShapeSource>& shapes) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& s : shapes) a.push_back(ShapeToJson(s));
    return a;
}

std::vector<ShapeSource> ShapesFromJson(const nlohmann::json& a, const char* key) {
    std::vector<ShapeSource> shapes;
    for (const auto& j : a.at(key)) shapes.push_back(ShapeFromJson(j));
    if (shapes.empty()) throw std::invalid_argument(std::string(key) + " is empty");
    return shapes;
}

}  // namespace

networks::TrainSample ToTrainSample(const Pair& p) {
    // The frame the learned methods run in (core/pair_normalization.hpp): a pair outside the
    // training frame, e.g. an indoor scan in its camera frame, is trained on as it is run.
    const PairNormalization frame = NormalizationOf(p.source, p.target);
    networks::TrainSample s;
    s.source = NormalizeCloud(p.source, frame);
    s.target = NormalizeCloud(p.target, frame);
    s.T_gt = NormalizeGroundTruth(p.T_gt, frame);
    s.source_overlap = p.source_overlap.cast<double>();
    s.target_overlap = p.target_overlap.cast<double>();
    return s;
}

networks::TrainData MakeTrainingData(const TrainingBundle& b) {
    networks::TrainData data;
    // Validation pairs come from another seed stream than training pairs.
    const std::uint64_t val_seed = b.seed ^ 0x76616c6964ULL;
    for (int i = 0; i < b.val_pairs; ++i) {
        data.validation.push_back(
            ToTrainSample(GeneratePair(b.val_shapes, b.protocol, val_seed, i)));
    }
    auto shapes = std::make_shared<std::vector<ShapeSource>>(b.train_shapes);
    data.train_pair = [shapes, options = b.protocol, seed = b.seed](std::uint64_t k) {
        return ToTrainSample(GeneratePair(*shapes, options, seed, k));
    };
    data.provenance = b.provenance;
    data.provenance["protocol"] = ProtocolProvenance(b.protocol);
    data.provenance["train_shapes"] = b.train_shapes.size();
    data.provenance["val_shapes"] = b.val_shapes.size();
    data.provenance["val_pairs"] = b.val_pairs;
    data.provenance["seed"] = b.seed;
    data.provenance["val_seed"] = val_seed;
    return data;
}

void WriteTrainingBundle(const std::string& path, const TrainingBundle& b) {
    const nlohmann::json j = {{"format", kFormat},
                              {"format_version", kFormatVersion},
                              {"protocol", b.protocol},
                              {"val_pairs", b.val_pairs},
                              {"seed", b.seed},
                              {"provenance", b.provenance},
                              {"config", b.config},
                              {"command", b.command},
                              {"length_given", b.length_given},
                              {"train_shapes", ShapesToJson(b.train_shapes)},
                              {"val_shapes", ShapesToJson(b.val_shapes)}};
    const std::vector<std::uint8_t> bytes = nlohmann::json::to_cbor(j);
    WriteFileAtomic(path,
                    std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

TrainingBundle ReadTrainingBundle(const std::string& path) {
    RequireRegularFile(path, "training bundle");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("training bundle " + path + " cannot be opened");
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
    try {
        const nlohmann::json j = nlohmann::json::from_cbor(bytes);
        if (!j.is_object() || j.value("format", std::string()) != kFormat) {
            throw std::invalid_argument("not a regbench training bundle");
        }
        if (j.at("format_version") != kFormatVersion) {
            throw std::invalid_argument("format_version " + j.at("format_version").dump() +
                                        ", this build reads " + std::to_string(kFormatVersion));
        }
        TrainingBundle b;
        b.protocol = ProtocolOptionsFromJson(j.at("protocol"), ProtocolOptions{});
        ValidateProtocolOptions(b.protocol);
        b.val_pairs = j.at("val_pairs").get<int>();
        if (b.val_pairs < 1) throw std::invalid_argument("val_pairs must be at least 1");
        b.seed = j.at("seed").get<std::uint64_t>();
        b.provenance = j.at("provenance");
        b.config = j.at("config");
        b.command = j.at("command").get<std::string>();
        b.length_given = j.at("length_given").get<bool>();
        b.train_shapes = ShapesFromJson(j, "train_shapes");
        b.val_shapes = ShapesFromJson(j, "val_shapes");
        return b;
    } catch (const std::exception& e) {
        throw std::runtime_error("training bundle " + path + ": " + e.what());
    }
}

}  // namespace regbench
