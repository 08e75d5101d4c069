// Triangle geometries (VK_GEOMETRY_TYPE_TRIANGLES_KHR) without motion: gathered as format::TriangleRecord, stored
// in format-2 triangle leaves (layout.hpp, TriangleLeaf; the build writes them, structure_build.cpp).
//   gather: every active triangle, fetched by chunks on several threads; degenerate ones only with ALLOW_UPDATE.
//   refit:  (triangles_update.cpp) the leaves re-fetched with the reader specialised for the geometry's kinds.
//   probe:  (triangles_update.cpp) active = no NaN vertex X.
#include <immintrin.h>

#include <cstddef>
#include <cstring>
#include <optional>
#include <vector>

#include "engine/util/host_memory.hpp"
#include "engine/assemble/kinds/kind.hpp"
#include "engine/assemble/kinds/triangle_vertices.hpp"
#include "engine/assemble/kinds/triangles_update.hpp"
#include "engine/assemble/refit_tree.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/opacity_micromaps.hpp"
#include "engine/input/triangles.hpp"
#include "engine/util/parallel_for.hpp"

namespace vkas {

using namespace format;
namespace {

// Fetches the active triangles of every triangle geometry into temp[] and refs[]; returns how many.
// Triangle number k of the build (geometries in order) is fetched into temp[k] by chunks, on several threads when
// the job has a ParallelFor; then the refs of the kept triangles are packed in order. refs[j].index names the
// triangle's temp slot, so the output does not depend on the chunking.
uint32_t gatherTriangles(const BuildJob& job, PrimRef* refs, std::byte* tempBytes) {
    auto* temp = reinterpret_cast<TriangleRecord*>(tempBytes);
    const auto& info = *job.info;
    const bool keepDegenerate = keepsDegenerate(info);
    struct Chunk {
        uint32_t geometry, begin, end;
        uint64_t base;  // build-wide number of the geometry's first triangle
    };
    constexpr uint32_t kChunk = 16384;
    HostVector<Chunk> chunks;
    uint64_t base = 0;
    for (uint32_t g = 0; g < info.geometryCount; ++g) {
        const uint32_t count = job.ranges[g].primitiveCount;
        if (buildGeometry(info, g).geometryType == VK_GEOMETRY_TYPE_TRIANGLES_KHR)
            for (uint32_t b = 0; b < count; b += kChunk) chunks.push_back({g, b, std::min(count, b + kChunk), base});
        base += count;
    }
    auto fetchChunk = [&](uint32_t c) {
        const Chunk& ch = chunks[c];
        const auto& geom = buildGeometry(info, ch.geometry);
        TriangleSource source(geom.geometry.triangles, job.ranges[ch.geometry]);
        // [EXT-OMM] "If the geometry includes an opacity micromap, the intersection candidate is determined as opaque
        // or non-opaque as described in Ray Opacity Micromap": the record says to look there.
        const uint32_t flags =
            recordFlags(geom.flags) | (opacityMicromapOf(geom.geometry.triangles) ? kTriangleMicromap : 0);
        // The reader specialised for the geometry's index type, vertex format and transform (no per-vertex dispatch).
        source.visit([&](auto reader) {
            using Reader = decltype(reader);
            uint32_t i = ch.begin;
            if constexpr (Reader::kVertex != TriangleVertexKind::Other && !Reader::kTransform) {
                // Float vertices without a transform, in SSE registers from load to record: the same values and
                // decisions as the general loop below (which takes over at the first NaN, whose quieting and
                // activity rules it applies); the box as Aabb::extend makes it (the first of equal values wins).
                for (; i < ch.end; ++i) {
                    const __m128 v0 = loadFloatVertex<Reader::kVertex>(reader.vertexPointer(i, 0));
                    const __m128 v1 = loadFloatVertex<Reader::kVertex>(reader.vertexPointer(i, 1));
                    const __m128 v2 = loadFloatVertex<Reader::kVertex>(reader.vertexPointer(i, 2));
                    const __m128 nan = _mm_or_ps(_mm_or_ps(_mm_cmpunord_ps(v0, v0), _mm_cmpunord_ps(v1, v1)),
                                                 _mm_cmpunord_ps(v2, v2));
                    if (_mm_movemask_ps(nan)) break;
                    const uint64_t k = ch.base + i;
                    uint32_t recFlags = flags;
                    if (isDegenerateTriangleSse(v0, v1, v2)) {
                        if (!keepDegenerate) {
                            refs[k].pad = 0;  // not kept
                            continue;
                        }
                        recFlags |= kTriangleDegenerate;
                    }
                    TriangleRecord& rec = temp[k];
                    // Overlapping stores: each vertex's zero lane 3 is overwritten by the next store.
                    _mm_storeu_ps(rec.v[0], v0);
                    _mm_storeu_ps(rec.v[1], v1);
                    _mm_storeu_ps(rec.v[2], v2);
                    rec.geometryIndex = ch.geometry;
                    rec.primitiveIndex = i;
                    rec.flags = recFlags;
                    const __m128 lower = _mm_min_ps(v2, _mm_min_ps(v1, v0));
                    const __m128 upper = _mm_max_ps(v2, _mm_max_ps(v1, v0));
                    const __m128 indexLane = _mm_castsi128_ps(_mm_set_epi32(int(uint32_t(k)), 0, 0, 0));
                    const __m128 keptLane = _mm_castsi128_ps(_mm_set_epi32(1, 0, 0, 0));
                    _mm_storeu_ps(refs[k].lower, _mm_or_ps(xyz(lower), indexLane));  // lower, index
                    _mm_storeu_ps(refs[k].upper, _mm_or_ps(xyz(upper), keptLane));   // upper, kept
                }
            }
            for (; i < ch.end; ++i) {
                const uint64_t k = ch.base + i;
                TriangleRecord& rec = temp[k];
                refs[k].pad = 0;  // not kept
                if (!reader.fetch(i, rec.v)) continue;  // inactive: never hit, never updated back to life
                rec.geometryIndex = ch.geometry;
                rec.primitiveIndex = i;
                rec.flags = flags;
                if (isDegenerateTriangle(rec.v)) {
                    if (!keepDegenerate) continue;
                    rec.flags |= kTriangleDegenerate;
                }
                Aabb b;
                for (auto& v : rec.v) b.extend(Vec3{v[0], v[1], v[2]});
                setPrimRef(refs[k], uint32_t(k), b);
                refs[k].pad = 1;  // kept
            }
        });
    };
    parallelFor(job.parallel, uint32_t(chunks.size()), fetchChunk);
    // Pack the refs of the kept triangles in order. The leading chunks whose triangles were all kept (usually all of
    // them) stay in place and only clear their flags, in parallel; the rest is packed serially.
    HostVector<uint8_t> whole(chunks.size());
    auto checkChunk = [&](uint32_t c) {
        const Chunk& ch = chunks[c];
        bool all = true;
        for (uint64_t k = ch.base + ch.begin; k < ch.base + ch.end; ++k) all = all && refs[k].pad != 0;
        if (all)
            for (uint64_t k = ch.base + ch.begin; k < ch.base + ch.end; ++k) refs[k].pad = 0;
        whole[c] = all;
    };
    parallelFor(job.parallel, uint32_t(chunks.size()), checkChunk);
    uint32_t n = 0;
    size_t c = 0;
    for (; c < chunks.size() && whole[c] && chunks[c].base + chunks[c].begin == n; ++c)
        n += chunks[c].end - chunks[c].begin;
    for (; c < chunks.size(); ++c) {
        const Chunk& ch = chunks[c];
        for (uint64_t k = ch.base + ch.begin; k < ch.base + ch.end; ++k)
            if (whole[c] || refs[k].pad) {
                refs[n] = refs[k];
                refs[n++].pad = 0;
            }
    }
    return n;
}

}  // namespace

const PrimitiveKind kTriangleKind{gatherTriangles, refitTriangles, triangleActivity};

}  // namespace vkas

