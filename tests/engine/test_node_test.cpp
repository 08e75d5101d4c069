// The ray / node test on its own: the SSE2 version (trace/node_intersector_sse.hpp) against a scalar reference written
// here from its documented rule, the AVX2 and AVX-512 versions (trace/node_intersector_avx2.hpp, node_intersector_avx512.hpp)
// against the SSE2 one and each other lane for lane, bit for bit, and all against double-precision slabs: a box
// the exact ray crosses is never rejected.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <string>

#include "engine/trace/instruction_set.hpp"
#include "engine/trace/node_intersector_avx2.hpp"
#include "engine/trace/node_intersector_avx512.hpp"
#include "engine/trace/node_intersector_sse.hpp"
#include "engine/trace/ray.hpp"
#include "vkas_test.hpp"

namespace {

using vkas::format::Node;
using vkas::format::kNodeWidth;
constexpr float kInf = std::numeric_limits<float>::infinity();

struct NodeTest : ::testing::Test {
    uint64_t seed = vt::chooseSeed();
    vt::Rng rng{seed};
    void SetUp() override {
        std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
        RecordProperty("VKAS_TEST_SEED", std::to_string(seed));
    }

    // A coordinate from a few regimes: ordinary, near zero, on a grid the rays also use (exact plane hits).
    float coordinate() {
        switch (rng.below(4)) {
            case 0: return rng.uniformf(-10.0f, 10.0f);
            case 1: return rng.uniformf(-1e-3f, 1e-3f);
            case 2: return float(rng.range(-4, 4));
            default: return rng.uniformf(-1e4f, 1e4f);
        }
    }

    // Eight child boxes: ordinary, flat (lower == upper on an axis), empty slots (+inf / -inf), inverted.
    Node randomNode() {
        alignas(64) Node n;
        std::memset(&n, 0, sizeof n);
        float* lower[3] = {n.lowerX, n.lowerY, n.lowerZ};
        float* upper[3] = {n.upperX, n.upperY, n.upperZ};
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            const uint32_t kind = rng.below(8);
            for (int a = 0; a < 3; ++a) {
                float lo = coordinate(), hi = coordinate();
                if (lo > hi) std::swap(lo, hi);
                if (kind == 1) hi = lo;           // flat
                if (kind == 2) lo = kInf, hi = -kInf;  // empty slot
                if (kind == 3) std::swap(lo, hi);  // inverted: never hit
                lower[a][i] = lo, upper[a][i] = hi;
            }
            n.child[i] = kind == 2 ? vkas::format::kEmptyRef : vkas::format::makeLeafRef(i, 1);
        }
        return n;
    }

    // A ray with some zero direction components (the NaN products of the slab test).
    void randomRay(float org[3], float dir[3]) {
        for (int a = 0; a < 3; ++a) {
            org[a] = coordinate();
            dir[a] = rng.coin(0.2) ? 0.0f : (rng.coin(0.1) ? -0.0f : rng.uniformf(-1.0f, 1.0f));
        }
        if (dir[0] == 0.0f && dir[1] == 0.0f && dir[2] == 0.0f) dir[rng.below(3)] = 1.0f;
    }
};

// The rule the SSE and AVX2 versions implement, one lane at a time (node_intersector_sse.hpp's comment): NaN-ignoring
// max / min over the three slabs, clamped to [tMin, tMax], a hit when tNear <= tFar * kFarSlack.
uint32_t referenceEntries(const Node& node, const vkas::ShearedRay& r, float tMin, float tMax, float out[8]) {
    const vkas::NodePlanes p(node, r);
    auto maxNoNan = [](float a, float b) { return b > a ? b : a; };
    auto minNoNan = [](float a, float b) { return b < a ? b : a; };
    uint32_t mask = 0;
    for (uint32_t i = 0; i < kNodeWidth; ++i) {
        float tNear = maxNoNan(tMin, (p.nearX[i] - r.org[0]) * r.invDir[0]);
        tNear = maxNoNan(tNear, (p.nearY[i] - r.org[1]) * r.invDir[1]);
        tNear = maxNoNan(tNear, (p.nearZ[i] - r.org[2]) * r.invDir[2]);
        float tFar = minNoNan(tMax, (p.farX[i] - r.org[0]) * r.invDir[0]);
        tFar = minNoNan(tFar, (p.farY[i] - r.org[1]) * r.invDir[1]);
        tFar = minNoNan(tFar, (p.farZ[i] - r.org[2]) * r.invDir[2]);
        out[i] = tNear <= tFar * vkas::kFarSlack ? tNear : kInf;
        if (out[i] != kInf) mask |= 1u << i;
    }
    return mask;
}

// Whether the exact ray (in double) meets box i of `node` within [tMin, tMax].
bool exactlyCrosses(const Node& n, uint32_t i, const float org[3], const float dir[3], float tMin, float tMax) {
    const float lo[3] = {n.lowerX[i], n.lowerY[i], n.lowerZ[i]}, hi[3] = {n.upperX[i], n.upperY[i], n.upperZ[i]};
    double t0 = tMin, t1 = tMax;
    for (int a = 0; a < 3; ++a) {
        if (!(lo[a] <= hi[a])) return false;
        if (dir[a] == 0.0f) {
            if (org[a] < lo[a] || org[a] > hi[a]) return false;
            continue;
        }
        double ta = (double(lo[a]) - org[a]) / dir[a], tb = (double(hi[a]) - org[a]) / dir[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    }
    return t0 <= t1;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST_F(NodeTest, sse_matches_the_scalar_rule_and_never_rejects_a_crossed_box) {
    for (int iter = 0; iter < 20000; ++iter) {
        const Node node = randomNode();
        float org[3], dir[3];
        randomRay(org, dir);
        vkas::ShearedRay r;
        vkas::prepareShearedRay(r, org, dir);
        const float tMin = rng.coin(0.5) ? 0.0f : rng.uniformf(0.0f, 5.0f);
        const float tMax = rng.coin(0.3) ? kInf : tMin + rng.uniformf(0.0f, 50.0f);
        alignas(32) float sse[8], ref[8];
        const uint32_t maskSse = vkas::childEntryDistances(node, r, tMin, tMax, sse);
        const uint32_t maskRef = referenceEntries(node, r, tMin, tMax, ref);
        ASSERT_EQ(maskSse, maskRef) << "iteration " << iter;
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            ASSERT_TRUE(sameBits(sse[i], ref[i])) << "iteration " << iter << " lane " << i;
            if (exactlyCrosses(node, i, org, dir, tMin, tMax)) {
                ASSERT_TRUE(maskSse & (1u << i)) << "iteration " << iter << " lane " << i << ": a crossed box rejected";
            }
        }
    }
}

TEST_F(NodeTest, avx2_lanes_equal_sse_lanes_bit_for_bit) {
#if VKAS_NODE_INTERSECTOR_AVX2
    if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "this CPU has no AVX2";
    for (int iter = 0; iter < 20000; ++iter) {
        alignas(64) const Node node = randomNode();
        float org[3], dir[3];
        randomRay(org, dir);
        vkas::ShearedRay r;
        vkas::prepareShearedRay(r, org, dir);
        const float tMin = rng.coin(0.5) ? 0.0f : rng.uniformf(0.0f, 5.0f);
        const float tMax = rng.coin(0.3) ? kInf : tMin + rng.uniformf(0.0f, 50.0f);
        alignas(32) float sse[8], avx[8];
        const uint32_t maskSse = vkas::childEntryDistances(node, r, tMin, tMax, sse);
        const uint32_t maskAvx = vkas::childEntryDistancesAvx2(node, r, tMin, tMax, avx);
        ASSERT_EQ(maskSse, maskAvx) << "iteration " << iter;
        for (uint32_t i = 0; i < kNodeWidth; ++i)
            ASSERT_TRUE(sameBits(sse[i], avx[i])) << "iteration " << iter << " lane " << i << ": " << sse[i] << " vs "
                                                  << avx[i];
    }
#else
    GTEST_SKIP() << "not an x86-64 build";
#endif
}

// The three node tests on the same nodes and rays, lane for lane: masks equal, every entry distance the same bits,
// and each lane of the AVX-512 test also what the scalar rule gives (the AVX-512 kernel's node test must not be an
// instruction set of its own: Embree's AVX2 and AVX-512 paths disagree, its issue #520).
TEST_F(NodeTest, avx512_lanes_equal_sse_and_avx2_lanes_bit_for_bit) {
#if VKAS_NODE_INTERSECTOR_AVX512
    if (!__builtin_cpu_supports("avx512f") || !__builtin_cpu_supports("avx512vl"))
        GTEST_SKIP() << "this CPU has no AVX-512F/VL";
    for (int iter = 0; iter < 20000; ++iter) {
        alignas(64) const Node node = randomNode();
        float org[3], dir[3];
        randomRay(org, dir);
        vkas::ShearedRay r;
        vkas::prepareShearedRay(r, org, dir);
        const float tMin = rng.coin(0.5) ? 0.0f : rng.uniformf(0.0f, 5.0f);
        const float tMax = rng.coin(0.3) ? kInf : tMin + rng.uniformf(0.0f, 50.0f);
        alignas(32) float sse[8], avx[8], avx512[8], ref[8];
        const uint32_t maskSse = vkas::childEntryDistances(node, r, tMin, tMax, sse);
        const uint32_t maskAvx = vkas::childEntryDistancesAvx2(node, r, tMin, tMax, avx);
        const uint32_t mask512 = vkas::childEntryDistancesAvx512(node, r, tMin, tMax, avx512);
        const uint32_t maskRef = referenceEntries(node, r, tMin, tMax, ref);
        ASSERT_EQ(mask512, maskSse) << "iteration " << iter;
        ASSERT_EQ(mask512, maskAvx) << "iteration " << iter;
        ASSERT_EQ(mask512, maskRef) << "iteration " << iter;
        for (uint32_t i = 0; i < kNodeWidth; ++i) {
            ASSERT_TRUE(sameBits(avx512[i], sse[i])) << "iteration " << iter << " lane " << i << ": " << avx512[i]
                                                     << " vs " << sse[i];
            ASSERT_TRUE(sameBits(avx512[i], avx[i])) << "iteration " << iter << " lane " << i;
            ASSERT_TRUE(sameBits(avx512[i], ref[i])) << "iteration " << iter << " lane " << i;
            if (exactlyCrosses(node, i, org, dir, tMin, tMax)) {
                ASSERT_TRUE(mask512 & (1u << i)) << "iteration " << iter << " lane " << i << ": a crossed box rejected";
            }
        }
    }
#else
    GTEST_SKIP() << "not an x86-64 build";
#endif
}

// The instruction-set registry (trace/instruction_set.hpp) that every trace kernel asks: the best the CPU has, or
// a lower one VKAS_TRACE_KERNEL names (CTest runs this group with the best, with sse2 and with avx2).
TEST(InstructionSet, follows_the_cpu_and_the_environment) {
    using vkas::TraceInstructionSet;
    TraceInstructionSet best = TraceInstructionSet::Sse2;
#if defined(__x86_64__)
    if (__builtin_cpu_supports("avx2")) best = TraceInstructionSet::Avx2;
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl")) best = TraceInstructionSet::Avx512;
#endif
    const char* forced = std::getenv("VKAS_TRACE_KERNEL");
    TraceInstructionSet expected = best;
    if (forced && std::string(forced) == "sse2") expected = TraceInstructionSet::Sse2;
    if (forced && std::string(forced) == "avx2" && best > TraceInstructionSet::Avx2) expected = TraceInstructionSet::Avx2;
    EXPECT_EQ(vkas::traceInstructionSet(), expected);
    EXPECT_EQ(vkas::traceInstructionSet(), expected);  // read once: the same answer
    std::cout << "trace kernels: " << vkas::instructionSetName(vkas::traceInstructionSet()) << std::endl;
}

// The instance transform in AVX (ray.hpp's transformRayAvx2, the batch kernel's) against transformRay bit for bit:
// the same double operations in the same order, on matrices and rays from ordinary values to zeros of both signs,
// infinities and NaN, so the object-space ray (and so every hit) is the same in both kernels and the query.
TEST_F(NodeTest, avx2_instance_transform_equals_scalar_bit_for_bit) {
#if defined(__x86_64__)
    if (!__builtin_cpu_supports("avx2")) GTEST_SKIP() << "this CPU has no AVX2";
    const float specials[] = {0.0f, -0.0f, 1.0f, -1.0f, kInf, -kInf, std::numeric_limits<float>::quiet_NaN(),
                              std::numeric_limits<float>::denorm_min(), 3.4e38f, 1e-30f};
    auto value = [&]() {
        if (rng.coin(0.15)) return specials[rng.below(uint32_t(std::size(specials)))];
        return coordinate();
    };
    for (int iter = 0; iter < 200000; ++iter) {
        float m[3][4], o[3], d[3];
        const bool identityLike = rng.coin(0.3);  // a rotation-free instance: zeros of both signs, ones
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c)
                m[r][c] = identityLike ? (r == c ? 1.0f : (rng.coin(0.5) ? 0.0f : -0.0f)) : value();
        for (int i = 0; i < 3; ++i) o[i] = value(), d[i] = value();
        float so[3], sd[3], vo[3], vd[3];
        vkas::transformRay(m, o, d, so, sd);
        vkas::transformRayAvx2(m, o, d, vo, vd);
        // Any NaN equals any NaN: which operand's NaN a sum passes on (its sign) is the compiler's choice for the
        // scalar code too, and no decision of a traversal reads a NaN's sign (every comparison with it is false).
        auto same = [](float a, float b) { return (std::isnan(a) && std::isnan(b)) || sameBits(a, b); };
        for (int i = 0; i < 3; ++i) {
            ASSERT_TRUE(same(so[i], vo[i])) << "iteration " << iter << " origin " << i << ": " << so[i] << " vs "
                                                << vo[i];
            ASSERT_TRUE(same(sd[i], vd[i])) << "iteration " << iter << " direction " << i << ": " << sd[i]
                                                << " vs " << vd[i];
        }
    }
#else
    GTEST_SKIP() << "not an x86-64 build";
#endif
}

}  // namespace
