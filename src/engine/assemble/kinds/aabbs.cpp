// AABB geometries (VK_GEOMETRY_TYPE_AABBS_KHR): format::AabbRecord, the box as given (already floats: the tree
// bounds it exactly). Motion builds keep these ordinary records: only the application knows how a box moves.
//   gather: every active box that is not inverted (VUIDs 03546-03548).
//   refit:  the box re-read; one made inactive or inverted by an invalid update becomes empty (never hit).
//   probe:  active = minX not NaN; storable = active and not inverted.
#include <cstddef>
#include <cstring>
#include <limits>
#include <optional>

#include "engine/assemble/kinds/kind.hpp"
#include "engine/assemble/refit_tree.hpp"
#include "engine/input/aabbs.hpp"
#include "engine/input/build_inputs.hpp"

namespace vkas {

using namespace format;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Fetches the active AABBs of every AABB geometry into temp[] and refs[]; returns how many. The tree bounds
// each box exactly: the inputs are floats already.
uint32_t gatherAabbs(const BuildJob& job, PrimRef* refs, std::byte* tempBytes) {
    auto* temp = reinterpret_cast<AabbRecord*>(tempBytes);
    const auto& info = *job.info;
    uint32_t n = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const auto& geom = buildGeometry(info, g);
        if (geom.geometryType != VK_GEOMETRY_TYPE_AABBS_KHR) continue;
        AabbSource source(geom.geometry.aabbs, job.ranges[g]);
        const uint32_t flags = recordFlags(geom.flags);
        for (uint32_t i = 0; i < source.primitiveCount(); ++i) {
            AabbRecord rec;
            std::memset(&rec, 0, sizeof rec);
            if (!source.fetch(i, rec.lower, rec.upper)) continue;  // inactive (minX NaN): still counts in indices
            if (isInvertedAabb(rec.lower, rec.upper)) continue;    // invalid input (VUIDs 03546-03548): never hit
            rec.geometryIndex = g;
            rec.primitiveIndex = i;
            rec.flags = flags;
            Aabb b;
            b.extend(Vec3{rec.lower[0], rec.lower[1], rec.lower[2]});
            b.extend(Vec3{rec.upper[0], rec.upper[1], rec.upper[2]});
            temp[n] = rec;
            setPrimRef(refs[n], n, b);
            ++n;
        }
    }
    return n;
}

struct AabbRefitter {
    static constexpr size_t kSize = sizeof(AabbRecord);
    const RefitJob& job;
    std::optional<AabbSource> source;
    uint32_t current = UINT32_MAX;
    explicit AabbRefitter(const RefitJob& j) : job(j) {}
    void operator()(const std::byte* in, std::byte* out, Aabb& box) {
        AabbRecord rec;
        std::memcpy(&rec, in, sizeof rec);
        const uint32_t g = rec.geometryIndex;
        if (g < job.info->geometryCount) {
            if (g != current) source.emplace(buildGeometry(*job.info, g).geometry.aabbs, job.ranges[g]), current = g;
            if (rec.primitiveIndex < source->primitiveCount()) {
                if (source->fetch(rec.primitiveIndex, rec.lower, rec.upper) && !isInvertedAabb(rec.lower, rec.upper)) {
                    box.extend(Vec3{rec.lower[0], rec.lower[1], rec.lower[2]});
                    box.extend(Vec3{rec.upper[0], rec.upper[1], rec.upper[2]});
                } else {  // invalid update: an empty box, never hit
                    for (int k = 0; k < 3; ++k) rec.lower[k] = kInf, rec.upper[k] = -kInf;
                }
            }
        }
        std::memcpy(out, &rec, sizeof rec);
    }
};

struct AabbProbe {
    const RefitJob& job;
    std::optional<AabbSource> aabbs;
    uint32_t current = UINT32_MAX;
    explicit AabbProbe(const RefitJob& j) : job(j) {}
    refit::RecordKey key(const std::byte* records, uint64_t j) const { return refit::recordKeyOf<AabbRecord>(records, j); }
    void probe(uint32_t g, uint32_t i, bool& active, bool& storable) {
        if (g != current) aabbs.emplace(buildGeometry(*job.info, g).geometry.aabbs, job.ranges[g]), current = g;
        float lo[3], hi[3];
        active = aabbs->fetch(i, lo, hi);
        storable = active && !isInvertedAabb(lo, hi);
    }
};

void refitAabbs(const RefitJob& job) { refit::runRefit<refit::PerRecord<AabbRefitter>>(job); }

ActivityViolation aabbActivity(const RefitJob& job) {
    AabbProbe probe(job);
    return refit::checkActivity(job, probe);
}

}  // namespace

const PrimitiveKind kAabbKind{gatherAabbs, refitAabbs, aabbActivity};

}  // namespace vkas
