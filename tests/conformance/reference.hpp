// The double-precision referee of a differential case: what the ray program must produce for each ray, derived
// from the spec rules and the scene's application data (never from either implementation's structures).
// Triangles come from the brute-force oracle (tests/support/oracle.hpp); AABBs and the procedural step are evaluated
// here, in double, exactly as diff_case.hpp defines them.
#pragma once

#include <oracle.hpp>

#include <memory>
#include <string>
#include <vector>

#include "diff_case.hpp"

namespace diff {

// One primitive the ray program may meet, with what the spec says about it.
struct Expected {
    uint32_t type = 0;  // candidate type: 0 triangle, 1 AABB
    uint32_t instanceId = 0, geometryIndex = 0, primitiveIndex = 0;
    bool optional = false;   // within rounding of an edge, a box face, tMin/tMax or edge-on: may or may not appear
    bool accepted = false;   // closest mode: becomes a hit (opaque, confirmed, or generated)
    bool acceptOptional = false;  // the accept decision itself is within rounding (procedural tHit vs tFar / tMax)
    bool noDuplicates = false;    // the geometry has NO_DUPLICATE_ANY_HIT_INVOCATION
    double t = 0;            // triangle: intersection t; AABB: the generated tHit
    double tTolerance = 0;
    oracle::Candidate triangle;  // triangles only
};

struct ExpectedRay {
    std::vector<Expected> candidates;  // every primitive the ray may meet in its [tMin, tMax]
    const Expected* find(uint32_t type, uint32_t instanceId, uint32_t geometryIndex, uint32_t primitiveIndex) const;
};

// Per-scene view: the oracle's triangles and the decoded AABBs of every BLAS, per instance.
class Reference {
  public:
    explicit Reference(const Scene& scene);
    ExpectedRay expect(const Ray& ray) const;

    // Facts the comparison uses to explain differences.
    bool isDegenerate(uint32_t instanceId, uint32_t geometryIndex, uint32_t primitiveIndex) const;
    // Whether the instance's BLAS has a primitive of the kind that makes lavapipe lose its neighbours
    // (lavapipe-notes 1): an inactive AABB, or a triangle made inactive by a NaN in its third vertex.
    bool blasHasInactivePrimitives(uint32_t instanceId) const;
    // Object-space vertices (after the geometry transform) of a triangle, for position fetch.
    const oracle::Triangle* triangle(uint32_t instanceId, uint32_t geometryIndex, uint32_t primitiveIndex) const;
    // The triangle of the instance's BLAS whose vertices are `positions` (within rounding), if any: explains
    // wrongly fetched positions. Returns false when none matches.
    bool findTriangle(uint32_t instanceId, const float positions[3][4], uint32_t* geometryIndex,
                      uint32_t* primitiveIndex) const;
    // The triangle at `index` when all geometries of the instance's BLAS are numbered as one array.
    const oracle::Triangle* triangleByBlasIndex(uint32_t instanceId, uint32_t index, uint32_t* geometryIndex,
                                                uint32_t* primitiveIndex) const;
    uint32_t instanceCount() const { return uint32_t(scene_.instances.size()); }
    const Scene& scene() const { return scene_; }

  private:
    struct Box {
        double lo[3], hi[3];
        bool active;
    };
    struct BlasView {
        std::shared_ptr<oracle::Blas> triangles;     // geometries in order; AABB geometries left empty
        std::vector<std::vector<Box>> boxes;         // per geometry (empty for triangle geometries)
        std::vector<uint32_t> geometryFlags;
        bool isAabb = false;
        bool hasInactive = false;
    };
    const Scene& scene_;
    std::vector<BlasView> blases_;
    oracle::Scene oracleScene_;
};

}  // namespace diff
