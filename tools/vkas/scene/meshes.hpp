// Procedural triangle meshes for the built-in scene. Positions are float; the AS builder encodes them in the
// vertex format a geometry asks for. Triangles are counter-clockwise seen from outside.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "vec_math.hpp"

namespace vkas_tool {

struct Mesh {
    std::string name;
    std::vector<Vec3> positions;
    std::vector<uint32_t> indices;  // empty: non-indexed, three consecutive positions per triangle
    std::vector<Vec3> normals;      // per position: smooth shading normals (face normals for non-indexed meshes)

    uint32_t triangleCount() const {
        return static_cast<uint32_t>((indices.empty() ? positions.size() : indices.size()) / 3);
    }
    uint32_t vertexIndex(uint32_t triangle, uint32_t corner) const {
        return indices.empty() ? 3 * triangle + corner : indices[3 * triangle + corner];
    }
    // Fills `normals` with area-weighted vertex normals.
    void computeNormals();
};

// Subdivided icosahedron on the unit sphere, indexed; `displace` (may be empty) scales each vertex radially.
Mesh makeIcosphere(int subdivisions, const std::function<float(Vec3)>& displace = {});
// (p, q) torus knot tube: `segments` along the curve, `sides` around the tube, indexed. Fits in about [-1.3, 1.3].
Mesh makeTorusKnot(int p, int q, int segments, int sides, float tubeRadius);
// Height field over [-halfSize, halfSize]^2 in XZ with `cells` x `cells` quads, indexed; y = height(x, z).
Mesh makeTerrain(int cells, float halfSize, const std::function<float(float, float)>& height);
// Axis-aligned box [-1, 1]^3, non-indexed (36 positions).
Mesh makeBox();
// `count` tetrahedra scattered in [-1, 1]^3 with random sizes, non-indexed (12 positions each).
Mesh makeTetrahedra(int count, uint64_t seed);

}  // namespace vkas_tool
