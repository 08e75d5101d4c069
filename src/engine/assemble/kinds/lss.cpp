// [NV-LSS] Linear swept sphere geometries (VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV): format::LssRecord, both
// endpoints and radii in application order and the end caps the end-caps mode leaves on.
//   gather: every active LSS with both radii >= 0 (VUID 10436); both radii 0 only with ALLOW_UPDATE (degenerate).
//   refit:  endpoints and radii re-read; the end caps stay (they follow from the indices, which must not change).
//   probe:  active = no NaN at either endpoint; storable = active and both radii >= 0.
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

uint32_t gatherLss(const BuildJob& job, PrimRef* refs, std::byte* tempBytes) {
    auto* temp = reinterpret_cast<LssRecord*>(tempBytes);
    const auto& info = *job.info;
    const bool keepDegenerate = keepsDegenerate(info);
    uint32_t n = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        SweptSpheresData data;
        if (geom.geometryType != VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV || !sweptSpheresData(geom, data)) continue;
        SweptSpheresSource source(data, job.ranges[g]);
        const uint32_t flags = recordFlags(geom.flags);
        for (uint32_t i = 0; i < source.primitiveCount(); ++i) {
            LssRecord rec;
            std::memset(&rec, 0, sizeof rec);
            const bool a = source.fetchVertex(source.vertexNumber(i, 0), rec.p0, rec.r0);
            const bool b = source.fetchVertex(source.vertexNumber(i, 1), rec.p1, rec.r1);
            if (!a || !b) continue;                                  // inactive
            if (!(rec.r0 >= 0.0f && rec.r1 >= 0.0f)) continue;       // invalid input: never hit
            rec.geometryIndex = g;
            rec.primitiveIndex = i;
            rec.flags = flags | source.endCaps(i);
            if (rec.r0 == 0.0f && rec.r1 == 0.0f) {  // degenerate: never hit; kept for an update
                if (!keepDegenerate) continue;
                rec.flags |= kSweptDegenerate;
            }
            double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            extendBall(lo, hi, rec.p0, rec.r0);
            extendBall(lo, hi, rec.p1, rec.r1);
            temp[n] = rec;
            setPrimRef(refs[n], n, ballsBox(lo, hi));
            ++n;
        }
    }
    return n;
}

struct LssRefitter {
    static constexpr size_t kSize = sizeof(LssRecord);
    SweptInputs inputs;
    explicit LssRefitter(const RefitJob& job) : inputs(job) {}
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        LssRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        const SweptSpheresSource* s = inputs.at(rec.geometryIndex);
        if (s && rec.primitiveIndex < s->primitiveCount()) {
            // The end caps stay as the build decided them: they follow from the index buffer, which an update
            // must not change.
            const bool a = s->fetchVertex(s->vertexNumber(rec.primitiveIndex, 0), rec.p0, rec.r0);
            const bool b = s->fetchVertex(s->vertexNumber(rec.primitiveIndex, 1), rec.p1, rec.r1);
            // Degenerate (both radii 0) is re-decided as for spheres.
            rec.flags &= ~kSweptDegenerate;
            if (a && b && rec.r0 >= 0.0f && rec.r1 >= 0.0f) {
                if (rec.r0 == 0.0f && rec.r1 == 0.0f) rec.flags |= kSweptDegenerate;
                double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
                extendBall(lo, hi, rec.p0, rec.r0);
                extendBall(lo, hi, rec.p1, rec.r1);
                box.extend(ballsBox(lo, hi));
            } else {
                rec.r0 = rec.r1 = std::numeric_limits<float>::quiet_NaN();  // invalid update: never hit
                rec.flags |= kSweptDegenerate;
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct LssProbe {
    SweptInputs inputs;
    explicit LssProbe(const RefitJob& job) : inputs(job) {}
    refit::RecordKey key(const std::byte* records, uint64_t j) const { return refit::recordKeyOf<LssRecord>(records, j); }
    void probe(uint32_t g, uint32_t i, bool& active, bool& storable) {
        active = storable = false;
        const SweptSpheresSource* s = inputs.at(g);
        if (!s) return;
        float p0[3], p1[3], r0, r1;
        const bool a = s->fetchVertex(s->vertexNumber(i, 0), p0, r0);
        const bool b = s->fetchVertex(s->vertexNumber(i, 1), p1, r1);
        active = a && b;
        storable = active && r0 >= 0.0f && r1 >= 0.0f;  // both radii 0 counts, as for spheres
    }
};

void refitLss(const RefitJob& job) { refit::runRefit<refit::PerRecord<LssRefitter>>(job); }

ActivityViolation activityLss(const RefitJob& job) {
    LssProbe probe(job);
    return refit::checkActivity(job, probe);
}

}  // namespace

const PrimitiveKind kLssKind{gatherLss, refitLss, activityLss};

}  // namespace vkas
