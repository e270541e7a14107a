#include "datasets/indoor_dataset.hpp"

#include <filesystem>
#include <stdexcept>

#include "core/rng.hpp"
#include "datasets/dataset_impl.hpp"
#include "datasets/indoor_sim.hpp"

namespace regbench {
namespace {

constexpr int kTrainScenes = 24;
constexpr int kValScenes = 6;
/// A Kinect (640 x 480, f = 525) downscaled by 4.
constexpr int kDownscale = 4;

std::pair<int, int> SceneRange(const std::string& split) {
    if (split == "all") return {0, kIndoorSimScenes};
    if (split == "train") return {0, kTrainScenes};
    if (split == "val") return {kTrainScenes, kTrainScenes + kValScenes};
    if (split == "test") return {kTrainScenes + kValScenes, kIndoorSimScenes};
    throw std::invalid_argument("indoor-sim: unknown split '" + split +
                                "' (use all, train, val or test)");
}

}  // namespace

std::vector<ShapeSource> LoadIndoorSimShapes(const std::string& split,
                                             const DatasetOptions& options) {
    const auto [first, last] = SceneRange(split);
    const std::string mesh_dir =
        (std::filesystem::path(detail::DataDir(options)) / "meshes").string();
    const FurnitureLibrary library = LoadFurnitureMeshes(mesh_dir);
    IndoorSimOptions sim;
    sim.image_width = 640 / kDownscale;
    sim.image_height = 480 / kDownscale;
    sim.fx = sim.fy = 525.0 / kDownscale;
    sim.cx = (sim.image_width - 1) / 2.0;
    sim.cy = (sim.image_height - 1) / 2.0;
    std::vector<ShapeSource> shapes;
    for (int scene = first; scene < last; ++scene) {
        auto rng = MakePairRng(options.seed, static_cast<std::uint64_t>(scene));
        IndoorScan scan = SimulateIndoorScan(sim, library, rng);
        shapes.push_back(ShapeSource::FromPoints(std::move(scan.points_camera),
                                                 "room_" + std::to_string(scene), "indoor_sim"));
    }
    return shapes;
}

}  // namespace regbench
