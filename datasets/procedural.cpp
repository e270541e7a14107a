#include "datasets/procedural.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <vector>

#include "core/math_constants.hpp"
#include "core/rng.hpp"

namespace regbench {
namespace {

constexpr int kSegments = 48;  ///< samples around every closed curve (longitude, tube section)
constexpr int kRings = 32;     ///< samples along every open parameter (latitude, profile)

using Vec3 = Eigen::Vector3d;

/// Accumulates triangle soups of several closed parts into one Mesh.
class MeshBuilder {
public:
    int AddVertex(const Vec3& p) {
        vertices_.push_back(p);
        return static_cast<int>(vertices_.size()) - 1;
    }
    void AddTriangle(int a, int b, int c) { faces_.emplace_back(a, b, c); }
    /// Two triangles for the quad a-b-c-d (counter-clockwise).
    void AddQuad(int a, int b, int c, int d) {
        AddTriangle(a, b, c);
        AddTriangle(a, c, d);
    }
    Mesh Build() const {
        Mesh mesh;
        mesh.vertices.resize(static_cast<Eigen::Index>(vertices_.size()), 3);
        for (std::size_t i = 0; i < vertices_.size(); ++i) {
            mesh.vertices.row(static_cast<Eigen::Index>(i)) = vertices_[i].transpose();
        }
        mesh.faces.resize(static_cast<Eigen::Index>(faces_.size()), 3);
        for (std::size_t i = 0; i < faces_.size(); ++i) {
            mesh.faces.row(static_cast<Eigen::Index>(i)) = faces_[i].transpose();
        }
        return mesh;
    }

private:
    std::vector<Vec3> vertices_;
    std::vector<Eigen::Vector3i> faces_;
};

/// Closed genus-0 surface f(u, v), u in [0, 2pi) periodic, v in [-pi/2, pi/2] with the poles
/// f(., -pi/2) and f(., pi/2) (like latitude/longitude).
void AddSphereLike(MeshBuilder& out, const std::function<Vec3(double, double)>& f) {
    const int south = out.AddVertex(f(0.0, -0.5 * kPi));
    std::vector<int> first_of_ring;
    for (int r = 1; r < kRings; ++r) {
        const double v = -0.5 * kPi + kPi * r / kRings;
        first_of_ring.push_back(out.AddVertex(f(0.0, v)));
        for (int s = 1; s < kSegments; ++s) out.AddVertex(f(2.0 * kPi * s / kSegments, v));
    }
    const int north = out.AddVertex(f(0.0, 0.5 * kPi));
    const auto at = [&](int ring, int s) { return first_of_ring[ring] + (s % kSegments); };
    const int last = static_cast<int>(first_of_ring.size()) - 1;
    for (int s = 0; s < kSegments; ++s) {
        out.AddTriangle(south, at(0, s + 1), at(0, s));
        out.AddTriangle(north, at(last, s), at(last, s + 1));
        for (int r = 0; r < last; ++r)
            out.AddQuad(at(r, s), at(r, s + 1), at(r + 1, s + 1), at(r + 1, s));
    }
}

/// Closed genus-1 surface f(u, v), both parameters periodic in [0, 2pi).
void AddTorusLike(MeshBuilder& out, const std::function<Vec3(double, double)>& f,
                  int u_steps = kSegments, int v_steps = kRings) {
    const int base = out.AddVertex(f(0.0, 0.0));
    for (int k = 1; k < u_steps * v_steps; ++k) {
        out.AddVertex(f(2.0 * kPi * (k / v_steps) / u_steps, 2.0 * kPi * (k % v_steps) / v_steps));
    }
    const auto at = [&](int i, int j) { return base + (i % u_steps) * v_steps + (j % v_steps); };
    for (int i = 0; i < u_steps; ++i) {
        for (int j = 0; j < v_steps; ++j)
            out.AddQuad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
    }
}

/// Signed power sign(x)|x|^e, the superquadric building block (Barr 1981).
double SignedPow(double x, double e) { return std::copysign(std::pow(std::abs(x), e), x); }

/// Surface of revolution about the axis through `origin` along `axis`: profile (radius,
/// height) points in order; the two ends are closed by poles on the axis.
void AddLathe(MeshBuilder& out, const std::vector<Eigen::Vector2d>& profile,
              const Vec3& origin = Vec3::Zero(), const Vec3& axis = Vec3::UnitZ()) {
    const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), axis);
    const auto place = [&](double r, double z, double u) {
        return Vec3(origin + q * Vec3(r * std::cos(u), r * std::sin(u), z));
    };
    const int south = out.AddVertex(place(0.0, profile.front().y(), 0.0));
    const int first = south + 1;
    const int n = static_cast<int>(profile.size());
    for (const auto& p : profile) {
        for (int s = 0; s < kSegments; ++s)
            out.AddVertex(place(p.x(), p.y(), 2.0 * kPi * s / kSegments));
    }
    const int north = out.AddVertex(place(0.0, profile.back().y(), 0.0));
    const auto at = [&](int ring, int s) { return first + ring * kSegments + (s % kSegments); };
    for (int s = 0; s < kSegments; ++s) {
        out.AddTriangle(south, at(0, s + 1), at(0, s));
        out.AddTriangle(north, at(n - 1, s), at(n - 1, s + 1));
        for (int r = 0; r + 1 < n; ++r)
            out.AddQuad(at(r, s), at(r, s + 1), at(r + 1, s + 1), at(r + 1, s));
    }
}

void AddCylinder(MeshBuilder& out, double radius, const Vec3& from, const Vec3& to) {
    const double length = (to - from).norm();
    AddLathe(out, {{radius, 0.0}, {radius, length}}, from, (to - from) / length);
}

/// Axis-aligned box with half extents `h` centred at `c`, rotated by `R` about its centre.
void AddBox(MeshBuilder& out, const Vec3& c, const Vec3& h,
            const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) {
    int corner[8];
    for (int k = 0; k < 8; ++k) {
        const Vec3 sign((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
        corner[k] = out.AddVertex(c + R * sign.cwiseProduct(h));
    }
    // Faces with outward normals: -x, +x, -y, +y, -z, +z.
    out.AddQuad(corner[0], corner[4], corner[6], corner[2]);
    out.AddQuad(corner[1], corner[3], corner[7], corner[5]);
    out.AddQuad(corner[0], corner[1], corner[5], corner[4]);
    out.AddQuad(corner[2], corner[6], corner[7], corner[3]);
    out.AddQuad(corner[0], corner[2], corner[3], corner[1]);
    out.AddQuad(corner[4], corner[5], corner[7], corner[6]);
}

void AddSuperellipsoid(MeshBuilder& out, const Vec3& centre, const Vec3& axes, double e1,
                       double e2) {
    AddSphereLike(out, [&](double u, double v) {
        const double cv = SignedPow(std::cos(v), e1);
        return Vec3(centre + Vec3(axes.x() * cv * SignedPow(std::cos(u), e2),
                                  axes.y() * cv * SignedPow(std::sin(u), e2),
                                  axes.z() * SignedPow(std::sin(v), e1)));
    });
}

double U(std::mt19937_64& rng, double lo, double hi) { return UniformReal(rng, lo, hi); }

// ---- categories (alphabetical = label order) ----

void MakeBottle(MeshBuilder& out, std::mt19937_64& rng) {
    const double body_r = U(rng, 0.25, 0.45), body_h = U(rng, 0.6, 1.1);
    const double neck_r = U(rng, 0.06, 0.5) * body_r, neck_h = U(rng, 0.2, 0.5);
    const double shoulder = U(rng, 0.1, 0.35);
    std::vector<Eigen::Vector2d> profile;
    for (int k = 0; k <= kRings; ++k) {
        const double z = (body_h + shoulder + neck_h) * k / kRings;
        double r = body_r;
        if (z > body_h + shoulder) {
            r = neck_r;
        } else if (z > body_h) {  // smooth cosine shoulder from body to neck radius
            const double t = (z - body_h) / shoulder;
            r = neck_r + (body_r - neck_r) * 0.5 * (1.0 + std::cos(kPi * t));
        }
        profile.emplace_back(r, z);
    }
    AddLathe(out, profile);
}

void MakeChair(MeshBuilder& out, std::mt19937_64& rng) {
    const double w = U(rng, 0.35, 0.55), d = U(rng, 0.35, 0.55), seat_z = U(rng, 0.4, 0.6);
    const double t = U(rng, 0.03, 0.07), leg = U(rng, 0.025, 0.05), back_h = U(rng, 0.4, 0.8);
    const double tilt = U(rng, 0.0, 0.3);
    AddBox(out, Vec3(0, 0, seat_z), Vec3(w, d, t));
    const Eigen::Matrix3d R = Eigen::AngleAxisd(-tilt, Vec3::UnitX()).toRotationMatrix();
    AddBox(out, Vec3(0, -d + t, seat_z + t) + R * Vec3(0, 0, back_h), Vec3(w, t, back_h), R);
    for (int k = 0; k < 4; ++k) {
        const double x = (k & 1 ? 1 : -1) * (w - leg), y = (k & 2 ? 1 : -1) * (d - leg);
        AddBox(out, Vec3(x, y, 0.5 * (seat_z - t)), Vec3(leg, leg, 0.5 * (seat_z - t)));
    }
}

void MakeDumbbell(MeshBuilder& out, std::mt19937_64& rng) {
    const double half_len = U(rng, 0.4, 0.9), bar_r = U(rng, 0.05, 0.15);
    const double e1 = U(rng, 0.3, 1.0), e2 = U(rng, 0.3, 1.0);
    const Vec3 weight(U(rng, 0.1, 0.3), U(rng, 0.25, 0.5), U(rng, 0.25, 0.5));
    const double asym = U(rng, 0.7, 1.0);  // one weight may be smaller
    AddCylinder(out, bar_r, Vec3(-half_len, 0, 0), Vec3(half_len, 0, 0));
    AddSuperellipsoid(out, Vec3(-half_len, 0, 0), weight, e1, e2);
    AddSuperellipsoid(out, Vec3(half_len, 0, 0), asym * weight, e1, e2);
}

void MakeGear(MeshBuilder& out, std::mt19937_64& rng) {
    const int teeth = 6 + static_cast<int>(UniformIndex(rng, 13));
    const double r_in = U(rng, 0.5, 0.8), r_out = r_in + U(rng, 0.1, 0.3), h = U(rng, 0.1, 0.4);
    const double hub_r = U(rng, 0.1, 0.3), hub_h = U(rng, 0.0, 0.4);
    // Star polygon: each tooth is a trapezoid (4 corners); extruded prism with fanned caps.
    std::vector<Eigen::Vector2d> polygon;
    for (int k = 0; k < teeth; ++k) {
        const double a = 2.0 * kPi * k / teeth, step = 2.0 * kPi / teeth;
        const double radii[4] = {r_in, r_out, r_out, r_in};
        const double offsets[4] = {0.0, 0.3, 0.5, 0.8};
        for (int c = 0; c < 4; ++c) {
            polygon.emplace_back(radii[c] * std::cos(a + offsets[c] * step),
                                 radii[c] * std::sin(a + offsets[c] * step));
        }
    }
    const int n = static_cast<int>(polygon.size());
    const int bottom_c = out.AddVertex(Vec3(0, 0, -h));
    const int top_c = out.AddVertex(Vec3(0, 0, h));
    const int first = out.AddVertex(Vec3(polygon[0].x(), polygon[0].y(), -h));
    out.AddVertex(Vec3(polygon[0].x(), polygon[0].y(), h));
    for (int k = 1; k < n; ++k) {
        out.AddVertex(Vec3(polygon[static_cast<std::size_t>(k)].x(),
                           polygon[static_cast<std::size_t>(k)].y(), -h));
        out.AddVertex(Vec3(polygon[static_cast<std::size_t>(k)].x(),
                           polygon[static_cast<std::size_t>(k)].y(), h));
    }
    for (int k = 0; k < n; ++k) {
        const int b0 = first + 2 * k, t0 = b0 + 1;
        const int b1 = first + 2 * ((k + 1) % n), t1 = b1 + 1;
        out.AddTriangle(bottom_c, b1, b0);
        out.AddTriangle(top_c, t0, t1);
        out.AddQuad(b0, b1, t1, t0);
    }
    if (hub_h > 0.05) AddCylinder(out, hub_r, Vec3(0, 0, -h - hub_h), Vec3(0, 0, h + hub_h));
}

void MakeLamp(MeshBuilder& out, std::mt19937_64& rng) {
    const double base_r = U(rng, 0.2, 0.4), base_h = U(rng, 0.03, 0.1);
    const double pole_h = U(rng, 0.6, 1.2), pole_r = U(rng, 0.02, 0.05);
    const double shade_bottom = U(rng, 0.25, 0.5), shade_top = U(rng, 0.08, 0.25);
    const double shade_h = U(rng, 0.2, 0.45);
    AddCylinder(out, base_r, Vec3(0, 0, 0), Vec3(0, 0, base_h));
    AddCylinder(out, pole_r, Vec3(0, 0, base_h), Vec3(0, 0, base_h + pole_h));
    const double z0 = base_h + pole_h - 0.5 * shade_h;
    AddLathe(out, {{shade_bottom, z0}, {shade_top, z0 + shade_h}});
}

void MakeMushroom(MeshBuilder& out, std::mt19937_64& rng) {
    const double stem_r = U(rng, 0.08, 0.2), stem_h = U(rng, 0.3, 0.8);
    const double cap_r = U(rng, 0.35, 0.7), cap_h = U(rng, 0.15, 0.5);
    const double flare = U(rng, 1.0, 1.6), droop = U(rng, 0.0, 0.12);
    std::vector<Eigen::Vector2d> profile = {
        {flare * stem_r, 0.0}, {stem_r, 0.5 * stem_h}, {stem_r, stem_h}};
    profile.emplace_back(cap_r, stem_h - droop);  // cap rim, possibly drooping below the gill
    for (int k = 1; k < kRings; ++k) {
        const double a = 0.5 * kPi * k / kRings;
        profile.emplace_back(cap_r * std::cos(a), stem_h + cap_h * std::sin(a));
    }
    AddLathe(out, profile);
}

void MakeSuperellipsoid(MeshBuilder& out, std::mt19937_64& rng) {
    const Vec3 axes(U(rng, 0.4, 1.0), U(rng, 0.4, 1.0), U(rng, 0.4, 1.0));
    AddSuperellipsoid(out, Vec3::Zero(), axes, U(rng, 0.2, 1.8), U(rng, 0.2, 1.8));
}

void MakeSupertoroid(MeshBuilder& out, std::mt19937_64& rng) {
    const double major = U(rng, 0.5, 0.9), minor = U(rng, 0.1, 0.4) * major;
    const double e1 = U(rng, 0.3, 1.5), e2 = U(rng, 0.3, 1.5), squash = U(rng, 0.6, 1.0);
    AddTorusLike(out, [&](double u, double v) {
        const double ring = major + minor * SignedPow(std::cos(v), e1);
        return Vec3(ring * SignedPow(std::cos(u), e2), squash * ring * SignedPow(std::sin(u), e2),
                    minor * SignedPow(std::sin(v), e1));
    });
}

void MakeTable(MeshBuilder& out, std::mt19937_64& rng) {
    const double w = U(rng, 0.5, 0.9), d = U(rng, 0.3, 0.7), height = U(rng, 0.4, 0.8);
    const double top_t = U(rng, 0.02, 0.06), leg = U(rng, 0.02, 0.06);
    const bool round_top = UniformIndex(rng, 2) == 1, pedestal = UniformIndex(rng, 3) == 0;
    if (round_top) {
        AddCylinder(out, w, Vec3(0, 0, height - top_t), Vec3(0, 0, height + top_t));
    } else {
        AddBox(out, Vec3(0, 0, height), Vec3(w, d, top_t));
    }
    if (pedestal) {
        AddCylinder(out, 2.0 * leg, Vec3(0, 0, 0), Vec3(0, 0, height - top_t));
        AddCylinder(out, 0.5 * d, Vec3(0, 0, 0), Vec3(0, 0, top_t));
        return;
    }
    const double ry = round_top ? 0.6 * w : d;
    const double rx = round_top ? 0.6 * w : w;
    for (int k = 0; k < 4; ++k) {
        const Vec3 foot((k & 1 ? 1 : -1) * (rx - 2 * leg), (k & 2 ? 1 : -1) * (ry - 2 * leg), 0);
        AddCylinder(out, leg, foot, foot + Vec3(0, 0, height - top_t));
    }
}

void MakeTorusKnot(MeshBuilder& out, std::mt19937_64& rng) {
    static const int kPq[][2] = {{2, 3}, {3, 2}, {2, 5}, {3, 4}, {3, 5}, {2, 7}};
    const auto& pq = kPq[UniformIndex(rng, 6)];
    const double p = pq[0], q = pq[1];
    const double major = U(rng, 1.5, 2.5), tube = U(rng, 0.15, 0.35), lift = U(rng, 0.6, 1.2);
    // Curve on a torus; the tube frame is the torus' own normal made orthogonal to the tangent.
    const auto curve = [&](double u) {
        return Vec3((major + std::cos(q * u)) * std::cos(p * u),
                    (major + std::cos(q * u)) * std::sin(p * u), -lift * std::sin(q * u));
    };
    AddTorusLike(
        out,
        [&](double u, double v) {
            const double h = 1e-4;
            const Vec3 c = curve(u);
            const Vec3 tangent = (curve(u + h) - curve(u - h)).normalized();
            const Vec3 d(std::cos(q * u) * std::cos(p * u), std::cos(q * u) * std::sin(p * u),
                         -std::sin(q * u));
            const Vec3 n = (d - d.dot(tangent) * tangent).normalized();
            const Vec3 b = tangent.cross(n);
            return Vec3((c + tube * (std::cos(v) * n + std::sin(v) * b)) / (major + 1.0));
        },
        4 * kSegments, kRings / 2);
}

using Maker = void (*)(MeshBuilder&, std::mt19937_64&);

struct Category {
    const char* name;
    Maker make;
};

const std::vector<Category>& CategoryTable() {
    static const std::vector<Category> table = {
        {"bottle", MakeBottle},
        {"chair", MakeChair},
        {"dumbbell", MakeDumbbell},
        {"gear", MakeGear},
        {"lamp", MakeLamp},
        {"mushroom", MakeMushroom},
        {"superellipsoid", MakeSuperellipsoid},
        {"supertoroid", MakeSupertoroid},
        {"table", MakeTable},
        {"torus_knot", MakeTorusKnot},
    };
    return table;
}

}  // namespace

const std::vector<std::string>& ProceduralCategories() {
    static const std::vector<std::string> names = [] {
        std::vector<std::string> out;
        for (const auto& c : CategoryTable()) out.emplace_back(c.name);
        return out;
    }();
    return names;
}

Mesh MakeProceduralShape(int label, std::uint64_t seed, std::uint64_t index) {
    const auto& table = CategoryTable();
    if (label < 0 || label >= static_cast<int>(table.size())) {
        throw std::invalid_argument("procedural: category label " + std::to_string(label) +
                                    " out of range [0, " + std::to_string(table.size()) + ")");
    }
    // One stream per (seed, category, index): shapes never depend on how many were made.
    std::mt19937_64 rng(PairSeed(PairSeed(seed, static_cast<std::uint64_t>(label)), index));
    MeshBuilder builder;
    table[static_cast<std::size_t>(label)].make(builder, rng);
    return builder.Build();
}

}  // namespace regbench
