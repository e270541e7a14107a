#include "datasets/dataset_shapes.hpp"

#include <stdexcept>
#include <utility>

#include "datasets/indoor_dataset.hpp"

namespace regbench {

std::vector<ShapeSource> LoadShapeSources(const Dataset& dataset) {
    std::vector<ShapeSource> shapes;
    shapes.reserve(dataset.size());
    for (std::size_t i = 0; i < dataset.size(); ++i) {
        ShapeRecord record = dataset.Get(i);
        if (record.mesh) {
            shapes.push_back(
                ShapeSource::FromMesh(std::move(*record.mesh), record.name, record.category));
        } else if (record.target && record.T_target_points) {
            // A stored pair (ICL-NUIM / DeepGMR test files): resampled from `points` like any
            // cloud, or used as stored by the `stored` pairing.
            shapes.push_back(
                ShapeSource::FromStoredPair(std::move(record.points), std::move(*record.target),
                                            *record.T_target_points, record.name, record.category));
        } else {
            shapes.push_back(
                ShapeSource::FromPoints(std::move(record.points), record.name, record.category));
        }
    }
    return shapes;
}

ShapeLoader DatasetShapeLoader(const DatasetOptions& options) {
    return [options](const std::string& name, const std::string& split) {
        if (name == "indoor-sim") return LoadIndoorSimShapes(split, options);
        const std::unique_ptr<Dataset> dataset = OpenDataset(name, split, options);
        return LoadShapeSources(*dataset);
    };
}

}  // namespace regbench
