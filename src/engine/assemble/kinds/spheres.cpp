// [NV-LSS] Sphere geometries (VK_GEOMETRY_TYPE_SPHERES_NV): format::SphereRecord, the decoded centre and radius.
//   gather: every active sphere with a radius >= 0 (negative: invalid input, VUID 10426); radius 0 only with
//           ALLOW_UPDATE, marked kSweptDegenerate (never hit; the box is the centre).
//   refit:  centre and radius re-read; degenerate re-decided.
//   probe:  active = no NaN in position or radius; storable = active and radius >= 0.
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

#include "engine/assemble/kinds/kind.hpp"
#include "engine/assemble/kinds/swept_common.hpp"
#include "engine/assemble/refit_tree.hpp"

namespace vkas {

using namespace format;

namespace {

uint32_t gatherSpheres(const BuildJob& job, PrimRef* refs, std::byte* tempBytes) {
    auto* temp = reinterpret_cast<SphereRecord*>(tempBytes);
    const auto& info = *job.info;
    const bool keepDegenerate = keepsDegenerate(info);
    uint32_t n = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        SweptSpheresData data;
        if (geom.geometryType != VK_GEOMETRY_TYPE_SPHERES_NV || !sweptSpheresData(geom, data)) continue;
        SweptSpheresSource source(data, job.ranges[g]);
        const uint32_t flags = recordFlags(geom.flags);
        for (uint32_t i = 0; i < source.primitiveCount(); ++i) {
            SphereRecord rec;
            std::memset(&rec, 0, sizeof rec);
            if (!source.fetchVertex(source.vertexNumber(i, 0), rec.center, rec.radius)) continue;  // inactive
            if (!(rec.radius >= 0.0f)) continue;  // negative radius: invalid input, never hit
            rec.geometryIndex = g;
            rec.primitiveIndex = i;
            rec.flags = flags;
            if (rec.radius == 0.0f) {  // degenerate: never hit; kept for an update that gives it a radius
                if (!keepDegenerate) continue;
                rec.flags |= kSweptDegenerate;
            }
            double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            extendBall(lo, hi, rec.center, rec.radius);
            temp[n] = rec;
            setPrimRef(refs[n], n, ballsBox(lo, hi));
            ++n;
        }
    }
    return n;
}

struct SphereRefitter {
    static constexpr size_t kSize = sizeof(SphereRecord);
    SweptInputs inputs;
    explicit SphereRefitter(const RefitJob& job) : inputs(job) {}
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        SphereRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        const SweptSpheresSource* s = inputs.at(rec.geometryIndex);
        if (s && rec.primitiveIndex < s->primitiveCount()) {
            const bool active = s->fetchVertex(s->vertexNumber(rec.primitiveIndex, 0), rec.center, rec.radius);
            // Degenerate is re-decided: a sphere that has a radius again is hit again, one that loses it is not
            // (its centre still counts in the box, as in an ALLOW_UPDATE build).
            rec.flags &= ~kSweptDegenerate;
            if (active && rec.radius >= 0.0f) {
                if (rec.radius == 0.0f) rec.flags |= kSweptDegenerate;
                double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
                extendBall(lo, hi, rec.center, rec.radius);
                box.extend(ballsBox(lo, hi));
            } else {
                rec.radius = -1.0f;  // invalid update: no ball, never hit
                rec.flags |= kSweptDegenerate;
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct SphereProbe {
    SweptInputs inputs;
    explicit SphereProbe(const RefitJob& job) : inputs(job) {}
    refit::RecordKey key(const std::byte* records, uint64_t j) const { return refit::recordKeyOf<SphereRecord>(records, j); }
    void probe(uint32_t g, uint32_t i, bool& active, bool& storable) {
        active = storable = false;
        const SweptSpheresSource* s = inputs.at(g);
        if (!s) return;
        float c[3], r;
        active = s->fetchVertex(s->vertexNumber(i, 0), c, r);
        storable = active && r >= 0.0f;  // zero radius counts: ALLOW_UPDATE builds keep it
    }
};

void refitSpheres(const RefitJob& job) { refit::runRefit<refit::PerRecord<SphereRefitter>>(job); }

ActivityViolation activitySpheres(const RefitJob& job) {
    SphereProbe probe(job);
    return refit::checkActivity(job, probe);
}

}  // namespace

const PrimitiveKind kSphereKind{gatherSpheres, refitSpheres, activitySpheres};

}  // namespace vkas
