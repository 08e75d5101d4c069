// [NV-motion] Triangle geometries of a motion bottom level: format::MotionTriangleRecord (positions at time 0 and 1).
//   gather: every triangle active at both times; degenerate ones are always kept (they may be degenerate at some
//           times only; traversal rejects a triangle degenerate at the ray time).
//   refit:  both times re-fetched, one record at a time.
//   probe:  active = no NaN vertex X at either time.
#include <cstddef>
#include <cstring>
#include <optional>

#include "engine/input/opacity_micromaps.hpp"
#include "engine/assemble/kinds/kind.hpp"
#include "engine/assemble/refit_tree.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/motion_inputs.hpp"
#include "engine/input/triangles.hpp"

namespace vkas {

using namespace format;

namespace {

// The time-1 vertex data of a motion triangle geometry: VkAccelerationStructureGeometryMotionTrianglesDataNV's
// vertexData with everything else (format, stride, indexing, transform) of time 0. A geometry without it, or with a
// NULL address (invalid), does not move.
VkAccelerationStructureGeometryTrianglesDataKHR trianglesAtTimeOne(
    const VkAccelerationStructureGeometryTrianglesDataKHR& triangles) {
    VkAccelerationStructureGeometryTrianglesDataKHR atOne = triangles;
    const auto* m = motion::findMotionTriangles(triangles);
    if (m && m->vertexData.hostAddress) atOne.vertexData = m->vertexData;
    return atOne;
}

// [NV-motion] gatherTriangles for a motion bottom level: every triangle geometry gives its time-0 positions
// (vertexData) and time-1 positions (VkAccelerationStructureGeometryMotionTrianglesDataNV::vertexData, same format,
// stride, indexing and geometry transform; a geometry without it does not move). A triangle is inactive when a
// vertex X is NaN at either time. Degenerate triangles are always kept: a triangle can be degenerate at some
// times only, and the intersection test rejects zero-area triangles anyway. The box is the union of both times'
// boxes, which holds the linear interpolation in between (interpolated coordinates never leave [v0, v1]).
uint32_t gatherMotionTriangles(const BuildJob& job, PrimRef* refs, std::byte* tempBytes) {
    auto* temp = reinterpret_cast<MotionTriangleRecord*>(tempBytes);
    const auto& info = *job.info;
    uint32_t n = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        if (geom.geometryType != VK_GEOMETRY_TYPE_TRIANGLES_KHR) continue;
        TriangleSource source(geom.geometry.triangles, job.ranges[g]);
        TriangleSource source1(trianglesAtTimeOne(geom.geometry.triangles), job.ranges[g]);
        const uint32_t flags = kTriangleMotion | recordFlags(geom.flags) |
                               (opacityMicromapOf(geom.geometry.triangles) ? kTriangleMicromap : 0);  // [EXT-OMM]
        for (uint32_t i = 0; i < source.primitiveCount(); ++i) {
            MotionTriangleRecord rec;
            std::memset(&rec, 0, sizeof rec);
            const bool active0 = source.fetch(i, rec.base.v);
            const bool active1 = source1.fetch(i, rec.v1);
            if (!active0 || !active1) continue;  // inactive: never hit, never updated back to life
            rec.base.geometryIndex = g;
            rec.base.primitiveIndex = i;
            rec.base.flags = flags;
            Aabb b;
            for (auto& v : rec.base.v) b.extend(Vec3{v[0], v[1], v[2]});
            for (auto& v : rec.v1) b.extend(Vec3{v[0], v[1], v[2]});
            temp[n] = rec;
            setPrimRef(refs[n], n, b);
            ++n;
        }
    }
    return n;
}

// Both times of an update's motion triangle geometries, one geometry at a time (as TriangleInputs in triangles.cpp).
class MotionTriangleInputs {
public:
    explicit MotionTriangleInputs(const RefitJob& job) : job_(job) {}
    bool at(uint32_t g, const TriangleSource*& t0, const TriangleSource*& t1) {
        if (g >= job_.info->geometryCount) return false;
        if (g != current_) {
            const auto& tri = buildGeometry(*job_.info, g).geometry.triangles;
            t0_.emplace(tri, job_.ranges[g]);
            t1_.emplace(trianglesAtTimeOne(tri), job_.ranges[g]);
            current_ = g;
        }
        t0 = &*t0_, t1 = &*t1_;
        return true;
    }

private:
    const RefitJob& job_;
    std::optional<TriangleSource> t0_, t1_;
    uint32_t current_ = UINT32_MAX;
};

struct MotionTriangleRefitter {
    static constexpr size_t kSize = sizeof(MotionTriangleRecord);
    MotionTriangleInputs inputs;
    explicit MotionTriangleRefitter(const RefitJob& job) : inputs(job) {}
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        MotionTriangleRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        const TriangleSource *t0 = nullptr, *t1 = nullptr;
        if (inputs.at(rec.base.geometryIndex, t0, t1) && rec.base.primitiveIndex < t0->primitiveCount()) {
            const bool a = t0->fetch(rec.base.primitiveIndex, rec.base.v);
            const bool b = t1->fetch(rec.base.primitiveIndex, rec.v1);
            // Motion triangles are never marked degenerate (the intersection test rejects zero area); only an
            // invalid update (a triangle made inactive) sets the flag, so that it is never hit.
            rec.base.flags &= ~kTriangleDegenerate;
            if (a && b) {
                for (auto& v : rec.base.v) box.extend(Vec3{v[0], v[1], v[2]});
                for (auto& v : rec.v1) box.extend(Vec3{v[0], v[1], v[2]});
            } else {
                rec.base.flags |= kTriangleDegenerate;
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct MotionTriangleProbe {
    MotionTriangleInputs inputs;
    explicit MotionTriangleProbe(const RefitJob& job) : inputs(job) {}
    refit::RecordKey key(const std::byte* records, uint64_t j) const {
        return refit::recordKeyOf<TriangleRecord, sizeof(MotionTriangleRecord)>(records, j);
    }
    void probe(uint32_t g, uint32_t i, bool& active, bool& storable) {
        active = storable = false;
        float v[3][3];
        const TriangleSource *t0, *t1;
        if (!inputs.at(g, t0, t1)) return;
        const bool a = t0->fetch(i, v);
        const bool b = t1->fetch(i, v);
        active = storable = a && b;
    }
};

void refitMotionTriangles(const RefitJob& job) { refit::runRefit<refit::PerRecord<MotionTriangleRefitter>>(job); }

ActivityViolation motionTriangleActivity(const RefitJob& job) {
    MotionTriangleProbe probe(job);
    return refit::checkActivity(job, probe);
}

}  // namespace

const PrimitiveKind kMotionTriangleKind{gatherMotionTriangles, refitMotionTriangles, motionTriangleActivity};

}  // namespace vkas
