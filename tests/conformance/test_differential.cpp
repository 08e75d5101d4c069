// Differential conformance: every case of scene_gen.hpp built and traced by vkas (host commands, host ray queries)
// and by Mesa's lavapipe (device commands, GLSL ray queries), compared ray by ray through compare.hpp.
// docs/CONFORMANCE.md explains the accepted differences. Set VKAS_TEST_SEED to replay a run and
// VKAS_DIFF_VARIANTS to change the number of cases per group (default 8).
#include <gtest/gtest.h>
#include <vkas/vkas.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>
#include <string>

#include "compare.hpp"
#include "lavapipe_side.hpp"
#include "reference.hpp"
#include "scene_gen.hpp"
#include "vkas_side.hpp"

namespace diff {
namespace {

struct Sides {
    std::unique_ptr<VkasSide> vkas;
    std::unique_ptr<LavapipeSide> lavapipe;
    std::string why;  // why lavapipe is unavailable
    Capabilities caps;
};

Sides& sides() {
    static Sides s = [] {
        Sides out;
        std::string why;
        out.vkas = VkasSide::create(&why);
        if (!out.vkas) throw std::runtime_error("vkas device: " + why);
        out.lavapipe = LavapipeSide::create(&out.why);
        if (out.lavapipe) {
            out.caps.vertexFormats = out.lavapipe->vertexFormats();
            out.caps.positionFetch = out.lavapipe->hasPositionFetch();
            std::printf("[ REFEREE  ] %s; %zu vertex formats; position fetch %s\n",
                        out.lavapipe->deviceDescription().c_str(), out.caps.vertexFormats.size(),
                        out.caps.positionFetch ? "yes" : "no");
        }
        return out;
    }();
    return s;
}

uint64_t chooseSeed() {
    if (const char* s = std::getenv("VKAS_TEST_SEED")) return std::strtoull(s, nullptr, 0);
    std::random_device rd;
    return (uint64_t(rd()) << 32) | rd();
}

uint32_t variantCount() {
    const char* s = std::getenv("VKAS_DIFF_VARIANTS");
    return s ? uint32_t(std::max(1L, std::strtol(s, nullptr, 10))) : 8u;
}

class Differential : public ::testing::TestWithParam<std::string> {};

TEST_P(Differential, VkasMatchesLavapipe) {
    Sides& s = sides();
    if (!s.lavapipe) {
        const char* require = std::getenv("VKAS_REQUIRE_LAVAPIPE");
        if (require && std::string(require) == "1") FAIL() << "lavapipe is installed but unusable: " << s.why;
        GTEST_SKIP() << "SKIPPED: lavapipe (Mesa >= 25 from bookworm-backports) is not available: " << s.why
                     << " -- run scripts/setup-lavapipe.sh";
    }
    const uint64_t seed = chooseSeed();
    std::printf("[   SEED   ] VKAS_TEST_SEED=%llu\n", (unsigned long long)seed);

    std::array<size_t, size_t(Verdict::Count)> tally{};
    std::array<std::string, size_t(Verdict::Count)> example;
    size_t rays = 0, failures = 0, vkasHits = 0;
    for (uint32_t variant = 0; variant < variantCount(); ++variant) {
        const uint64_t caseSeed = seed + variant;
        const Case c = makeCase(GetParam(), variant, caseSeed, s.caps);
        std::vector<Result> v, l;
        ASSERT_NO_THROW(v = s.vkas->run(c.scene, c.rays)) << c.scene.name << " seed " << caseSeed;
        ASSERT_NO_THROW(l = s.lavapipe->run(c.scene, c.rays)) << c.scene.name << " seed " << caseSeed;
        ASSERT_EQ(v.size(), c.rays.size());
        ASSERT_EQ(l.size(), c.rays.size());
        const Reference reference(c.scene);
        for (size_t i = 0; i < c.rays.size(); ++i) {
            RayVerdict r = compareRay(reference, c.rays[i], v[i], l[i]);
            // Watertightness: a ray through a vertex or an edge of a closed surface crosses it exactly once.
            const int32_t crossings = c.crossings[i];
            if (crossings >= 0 && c.rays[i].mode == kModeCount && !isFailure(r.verdict)) {
                if (v[i].candidateCount != uint32_t(crossings))
                    r = {Verdict::VkasWrong, "vkas returned " + std::to_string(v[i].candidateCount) +
                                                 " candidates for a ray crossing the surface " +
                                                 std::to_string(crossings) + " time(s)"};
                else if (l[i].candidateCount < uint32_t(crossings))
                    r = {Verdict::Mismatch, "lavapipe returned " + std::to_string(l[i].candidateCount) +
                                                " candidates for a ray crossing the surface " +
                                                std::to_string(crossings) + " time(s)"};
                else if (l[i].candidateCount > uint32_t(crossings) && r.verdict == Verdict::Identical)
                    r = {Verdict::LavapipeSharedEdge, "lavapipe returned " + std::to_string(l[i].candidateCount) +
                                                          " candidates at one crossing"};
            }
            ++rays;
            vkasHits += v[i].committedType != 0;
            ++tally[size_t(r.verdict)];
            if (example[size_t(r.verdict)].empty() && r.verdict != Verdict::Identical)
                example[size_t(r.verdict)] = r.detail;
            if (std::getenv("VKAS_DIFF_VERBOSE") && r.verdict != Verdict::Identical)
                std::printf("[ VERBOSE  ] ray %zu %s: %s\n", i, verdictName(r.verdict), r.detail.c_str());
            if (isFailure(r.verdict) && ++failures <= 10)
                ADD_FAILURE() << verdictName(r.verdict) << " in " << c.scene.name << " (VKAS_TEST_SEED=" << seed
                              << "), ray " << i << ": " << r.detail << "\n  ray      " << describe(c.rays[i])
                              << "\n  vkas     " << describe(v[i]) << "\n  lavapipe " << describe(l[i]);
        }
    }
    std::printf("[ VERDICTS ] %s: %zu rays, %zu vkas hits; lavapipe given firstVertex folded into the address for "
                "%zu geometries so far\n",
                GetParam().c_str(), rays, vkasHits, s.lavapipe->foldedFirstVertexGeometries());
    for (size_t k = 0; k < tally.size(); ++k)
        if (tally[k])
            std::printf("[ VERDICTS ]   %-24s %6zu%s%s\n", verdictName(Verdict(k)), tally[k],
                        example[k].empty() ? "" : "  e.g. ", example[k].c_str());
    EXPECT_EQ(failures, 0u) << "unexplained differences (seed " << seed << ")";
}

INSTANTIATE_TEST_SUITE_P(ray_query, Differential, ::testing::ValuesIn(caseGroups()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

}  // namespace
}  // namespace diff
