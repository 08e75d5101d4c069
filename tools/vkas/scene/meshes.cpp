#include "meshes.hpp"

#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

namespace vkas_tool {

void Mesh::computeNormals() {
    normals.assign(positions.size(), Vec3{});
    for (uint32_t t = 0; t < triangleCount(); ++t) {
        uint32_t i0 = vertexIndex(t, 0), i1 = vertexIndex(t, 1), i2 = vertexIndex(t, 2);
        Vec3 n = cross(positions[i1] - positions[i0], positions[i2] - positions[i0]);  // length = 2 * area
        normals[i0] = normals[i0] + n;
        normals[i1] = normals[i1] + n;
        normals[i2] = normals[i2] + n;
    }
    for (Vec3& n : normals) n = normalize(n);
}

Mesh makeIcosphere(int subdivisions, const std::function<float(Vec3)>& displace) {
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    Mesh mesh;
    mesh.name = "icosphere";
    mesh.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                      {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    for (Vec3& p : mesh.positions) p = normalize(p);
    mesh.indices = {0, 11, 5, 0, 5,  1,  0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                    4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                    6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            auto key = std::minmax(a, b);
            auto [it, inserted] = midpoints.try_emplace({key.first, key.second}, 0u);
            if (inserted) {
                it->second = static_cast<uint32_t>(mesh.positions.size());
                mesh.positions.push_back(normalize(mesh.positions[a] + mesh.positions[b]));
            }
            return it->second;
        };
        std::vector<uint32_t> next;
        next.reserve(mesh.indices.size() * 4);
        for (size_t i = 0; i < mesh.indices.size(); i += 3) {
            uint32_t a = mesh.indices[i], b = mesh.indices[i + 1], c = mesh.indices[i + 2];
            uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        mesh.indices = std::move(next);
    }
    if (displace)
        for (Vec3& p : mesh.positions) p = p * displace(p);
    mesh.computeNormals();
    return mesh;
}

Mesh makeTorusKnot(int p, int q, int segments, int sides, float tubeRadius) {
    Mesh mesh;
    mesh.name = "torus knot";
    auto curve = [&](float u) {
        float r = 0.8f + 0.35f * std::cos(q * u);
        return Vec3{r * std::cos(p * u), 0.35f * std::sin(q * u), r * std::sin(p * u)};
    };
    const float tau = 2.0f * std::numbers::pi_v<float>;
    for (int i = 0; i < segments; ++i) {
        float u = tau * i / segments;
        Vec3 c = curve(u);
        Vec3 tangent = normalize(curve(u + 1e-3f) - curve(u - 1e-3f));
        Vec3 n = normalize(cross(tangent, Vec3{0, 1, 0}) + cross(tangent, c) * 0.3f);
        Vec3 b = normalize(cross(tangent, n));
        n = cross(b, tangent);
        for (int j = 0; j < sides; ++j) {
            float v = tau * j / sides;
            mesh.positions.push_back(c + (n * std::cos(v) + b * std::sin(v)) * tubeRadius);
        }
    }
    for (int i = 0; i < segments; ++i) {
        for (int j = 0; j < sides; ++j) {
            uint32_t a = i * sides + j, b = ((i + 1) % segments) * sides + j;
            uint32_t c = ((i + 1) % segments) * sides + (j + 1) % sides, d = i * sides + (j + 1) % sides;
            mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
        }
    }
    mesh.computeNormals();
    return mesh;
}

Mesh makeTerrain(int cells, float halfSize, const std::function<float(float, float)>& height) {
    Mesh mesh;
    mesh.name = "terrain";
    const int n = cells + 1;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            float x = -halfSize + 2.0f * halfSize * i / cells, z = -halfSize + 2.0f * halfSize * j / cells;
            mesh.positions.push_back({x, height(x, z), z});
        }
    }
    for (int j = 0; j < cells; ++j) {
        for (int i = 0; i < cells; ++i) {
            uint32_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
            // Seen from +Y, counter-clockwise: a -> c -> b and b -> c -> d.
            mesh.indices.insert(mesh.indices.end(), {a, c, b, b, c, d});
        }
    }
    mesh.computeNormals();
    return mesh;
}

Mesh makeBox() {
    Mesh mesh;
    mesh.name = "box";
    // One face per axis direction: (normal axis, sign).
    for (int axis = 0; axis < 3; ++axis) {
        for (float sign : {-1.0f, 1.0f}) {
            int u = (axis + 1) % 3, v = (axis + 2) % 3;
            if (sign < 0) std::swap(u, v);  // keep the winding counter-clockwise seen from outside
            auto corner = [&](float a, float b) {
                float c[3];
                c[axis] = sign, c[u] = a, c[v] = b;
                return Vec3{c[0], c[1], c[2]};
            };
            Vec3 p00 = corner(-1, -1), p10 = corner(1, -1), p11 = corner(1, 1), p01 = corner(-1, 1);
            mesh.positions.insert(mesh.positions.end(), {p00, p10, p11, p00, p11, p01});
        }
    }
    mesh.computeNormals();
    return mesh;
}

Mesh makeTetrahedra(int count, uint64_t seed) {
    Mesh mesh;
    mesh.name = "tetrahedra";
    Rng rng(seed);
    const std::array<Vec3, 4> unit = {Vec3{1, 1, 1}, Vec3{1, -1, -1}, Vec3{-1, 1, -1}, Vec3{-1, -1, 1}};
    for (int k = 0; k < count; ++k) {
        Vec3 center{rng.uniform(-0.8f, 0.8f), rng.uniform(-0.8f, 0.8f), rng.uniform(-0.8f, 0.8f)};
        float size = rng.uniform(0.05f, 0.2f);
        Affine r = Affine::rotation({rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.1f, 1)},
                                    rng.uniform(0, 6.28f));
        std::array<Vec3, 4> v;
        for (int i = 0; i < 4; ++i) v[i] = center + r.vector(unit[i]) * size;
        // Faces opposite each vertex, wound so that the normal points away from the opposite vertex.
        const int faces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
        for (const auto& f : faces) {
            Vec3 a = v[f[0]], b = v[f[1]], c = v[f[2]];
            Vec3 opposite = v[0] + v[1] + v[2] + v[3] - a - b - c;
            if (dot(cross(b - a, c - a), a - opposite) < 0) std::swap(b, c);
            mesh.positions.insert(mesh.positions.end(), {a, b, c});
        }
    }
    mesh.computeNormals();
    return mesh;
}

}  // namespace vkas_tool
