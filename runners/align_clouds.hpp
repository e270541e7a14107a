#pragma once
// `regbench align`: two point files registered with any registered method, optionally after
// moving both into the unit sphere with one similarity (and mapping the result back).
#include <string>

#include "core/point_cloud.hpp"
#include "core/registration.hpp"

namespace regbench {

/// x -> scale * (x - centre), applied to both clouds.
struct Normalization {
    Eigen::RowVector3d centre = Eigen::RowVector3d::Zero();
    double scale = 1.0;
};

/// The target's centroid and the reciprocal of the largest distance from it over both clouds:
/// both clouds then fit the unit sphere, keeping their relative pose.
Normalization FitNormalization(const PointCloud& source, const PointCloud& target);
/// Applies the normalisation to a cloud.
PointCloud Normalize(const PointCloud& points, const Normalization& n);
/// The transform between the original clouds from one between the normalised ones:
/// target' = R source' + t' means target = R source + t with t = t' / scale - R c + c.
Transform Denormalize(const Transform& T_normalized, const Normalization& n);

/// Runs `method` on the clouds (normalised first when `normalize`); the result's transform is
/// in the clouds' own frame either way.
AlignResult AlignClouds(RegistrationMethod& method, const PointCloud& source,
                        const PointCloud& target, bool normalize, const AlignContext& context);

}  // namespace regbench
