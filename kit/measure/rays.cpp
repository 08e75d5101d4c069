#include "rays.hpp"

#include <random>
#include <stdexcept>

namespace vb {
namespace {

struct V3 {
    double x, y, z;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(V3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 normalize(V3 a) { return a * (1 / std::sqrt(dot(a, a))); }

V3 center(const Box& b) {
    return {0.5 * (double(b.lo[0]) + b.hi[0]), 0.5 * (double(b.lo[1]) + b.hi[1]), 0.5 * (double(b.lo[2]) + b.hi[2])};
}

// World-space vertex `i` of the mesh under instance `inst` (none for a single-mesh scene).
V3 worldVertex(const Scene& s, int32_t inst, uint32_t i) {
    const float* p = &s.mesh.vertices[3 * i];
    if (!s.manyInstances()) return {p[0], p[1], p[2]};
    const Transform& x = s.instances[size_t(inst)];
    return {x[0] * p[0] + x[1] * p[1] + x[2] * p[2] + x[3], x[4] * p[0] + x[5] * p[1] + x[6] * p[2] + x[7],
            x[8] * p[0] + x[9] * p[1] + x[10] * p[2] + x[11]};
}

VkasRay makeRay(V3 o, V3 d, float tMin, float tMax) {
    return {{float(o.x), float(o.y), float(o.z)}, tMin, {float(d.x), float(d.y), float(d.z)}, tMax};
}

}  // namespace

std::vector<VkasRay> cameraRays(const Scene& scene, size_t count) {
    const Box b = sceneBounds(scene);
    const double r = 0.5 * b.diagonal();
    const V3 target = center(b);
    const V3 back = normalize({0.5, 0.6, 1.0});  // the camera sits above and in front (y is up in these files)
    const double halfFov = 20 * M_PI / 180;
    const V3 eye = target + back * (0.8 * r / std::sin(halfFov));
    const V3 fwd = back * -1.0, right = normalize(cross(fwd, {0, 1, 0})), up = cross(right, fwd);
    const size_t side = size_t(std::ceil(std::sqrt(double(count))));
    const double scale = std::tan(halfFov);
    std::vector<VkasRay> rays;
    rays.reserve(count);
    for (size_t i = 0; i < count; ++i) {
        const double sx = (2 * ((i % side) + 0.5) / side - 1) * scale, sy = (1 - 2 * ((i / side) + 0.5) / side) * scale;
        rays.push_back(makeRay(eye, normalize(fwd + right * sx + up * sy), 0, INFINITY));
    }
    return rays;
}

std::vector<VkasRay> secondaryRays(const Scene& scene, RayKind kind, const std::vector<VkasRay>& camera,
                                   const std::vector<Hit>& cameraHits, size_t count) {
    std::vector<size_t> hitRays;
    for (size_t i = 0; i < cameraHits.size(); ++i)
        if (cameraHits[i].hit()) hitRays.push_back(i);
    if (hitRays.empty()) throw std::runtime_error(scene.name + ": no camera ray hits the scene");
    const Box b = sceneBounds(scene);
    const double r = 0.5 * b.diagonal(), eps = 1e-5 * r;
    const V3 light = center(b) + V3{0.3, 1.0, 0.4} * r;
    std::mt19937 rng(kind == RayKind::Diffuse ? 11 : 13);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<VkasRay> rays;
    rays.reserve(count);
    for (size_t k = 0; k < count; ++k) {
        const size_t i = hitRays[k % hitRays.size()];
        const Hit& h = cameraHits[i];
        const VkasRay& c = camera[i];
        const V3 d = {c.direction[0], c.direction[1], c.direction[2]};
        const V3 p = V3{c.origin[0], c.origin[1], c.origin[2]} + d * h.t;
        const uint32_t* tri = &scene.mesh.indices[3 * size_t(h.prim)];
        const V3 a = worldVertex(scene, h.inst, tri[0]);
        V3 n = normalize(cross(worldVertex(scene, h.inst, tri[1]) - a, worldVertex(scene, h.inst, tri[2]) - a));
        if (dot(n, d) > 0) n = n * -1.0;  // facing the camera ray
        const V3 o = p + n * eps;
        if (kind == RayKind::Diffuse) {
            // Cosine-weighted direction about n.
            const V3 t = normalize(std::abs(n.x) > 0.5 ? cross(n, {0, 1, 0}) : cross(n, {1, 0, 0})), s = cross(n, t);
            const double phi = 2 * M_PI * u(rng), r2 = u(rng), sr = std::sqrt(r2);
            const V3 dir = normalize(t * (sr * std::cos(phi)) + s * (sr * std::sin(phi)) + n * std::sqrt(1 - r2));
            rays.push_back(makeRay(o, dir, 0, INFINITY));
        } else {
            const V3 toLight = light - o;
            const double dist = std::sqrt(dot(toLight, toLight));
            rays.push_back(makeRay(o, toLight * (1 / dist), 0, float(dist * (1 - 1e-6))));
        }
    }
    return rays;
}

}  // namespace vb
