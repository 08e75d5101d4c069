// The packet kernel (engine/trace/packet_intersectors.hpp, packet_kernel_body.hpp) against the single-ray kernel:
//   - the group test never drops a child that one of the packet's rays enters (as the single-ray node test decides
//     it, with that ray's own tMin and tMax), and bounds each entry distance from below; the lane test decides
//     every ray exactly as the single-ray test does. Random nodes and packets, with planes through the rays' own
//     points, through their origins, flat and empty boxes, nearly axis-parallel rays, coherent and scattered rays.
//   - tracePacket gives each ray of a packet traceKernel's hit bit for bit (type, t, barycentrics, facing, instance,
//     geometry and primitive), except the rays it reports as tied, on scenes with duplicated triangles (ties),
//     many instances with every instance flag and mask, and every ray flag but TerminateOnFirstHit (which never
//     forms a packet).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <iostream>
#include <vector>

#include "api/device.hpp"  // resolveAccelerationStructure: instance references to blocks, as vkasTraceRays does
#include "engine/format/layout.hpp"
#include "engine/trace/batch_kernel.hpp"
#include "engine/trace/node_intersector_sse.hpp"
#include "engine/trace/packet_gather.hpp"
#include "engine/trace/packet_intersectors.hpp"
#include "meshes.hpp"

using namespace vt;

namespace {

// ---- The group test and the lane test ---------------------------------------------------------------------------

struct LaneRay {
    vkas::ShearedRay ray;
    float tMin, tMax;
};

float signedIn(Rng& rng, bool negative, float lo, float hi) {
    const float v = rng.uniformf(lo, hi);
    return negative ? -v : v;
}

// Rays of one octant: a shared origin with jitter (coherent) or scattered; some direction components tiny.
std::vector<LaneRay> randomPacket(Rng& rng, uint32_t count, const bool negative[3]) {
    const bool coherent = rng.coin();
    float base[3], dir[3];
    for (int a = 0; a < 3; ++a) base[a] = rng.uniformf(-4, 4), dir[a] = signedIn(rng, negative[a], 0.05f, 1.0f);
    std::vector<LaneRay> rays(count);
    for (auto& r : rays) {
        float o[3], d[3];
        for (int a = 0; a < 3; ++a) {
            o[a] = coherent ? base[a] + rng.uniformf(-1e-3f, 1e-3f) : rng.uniformf(-4, 4);
            d[a] = coherent ? dir[a] + signedIn(rng, negative[a], 0.0f, 0.02f) : signedIn(rng, negative[a], 0.0f, 1.0f);
            if (rng.coin(0.05)) d[a] = negative[a] ? -1e-20f : 1e-20f;  // nearly parallel to a plane
            if (d[a] == 0.0f) d[a] = negative[a] ? -1e-3f : 1e-3f;
        }
        vkas::prepareShearedRay(r.ray, o, d);
        r.tMin = rng.coin(0.7) ? 0.0f : rng.uniformf(0, 2);
        r.tMax = rng.coin(0.3) ? INFINITY : r.tMin + rng.uniformf(0, 10);
    }
    return rays;
}

// A node whose children are random boxes, some with a plane through a ray's point at a random t or through a
// ray's origin, some flat, some empty slots.
vkas::format::Node randomNode(Rng& rng, const std::vector<LaneRay>& rays) {
    vkas::format::Node node{};
    for (uint32_t i = 0; i < vkas::format::kNodeWidth; ++i) {
        float lo[3], hi[3];
        const LaneRay& r = rays[rng.below(uint32_t(rays.size()))];
        const float t = rng.coin(0.5) ? r.tMin : rng.uniformf(0, 8);
        for (int a = 0; a < 3; ++a) {
            const float p = rng.coin(0.2) ? r.ray.org[a] : r.ray.org[a] + t * r.ray.dir[a];
            const float size = rng.coin(0.1) ? 0.0f : rng.uniformf(0, rng.coin() ? 0.05f : 3.0f);
            // the point on the lower plane, the upper plane, or inside
            const int where = int(rng.below(3));
            lo[a] = where == 0 ? p : where == 1 ? p - size : p - 0.5f * size;
            hi[a] = lo[a] + size;
        }
        const bool empty = rng.coin(0.1);
        node.lowerX[i] = empty ? INFINITY : lo[0], node.upperX[i] = empty ? -INFINITY : hi[0];
        node.lowerY[i] = empty ? INFINITY : lo[1], node.upperY[i] = empty ? -INFINITY : hi[1];
        node.lowerZ[i] = empty ? INFINITY : lo[2], node.upperZ[i] = empty ? -INFINITY : hi[2];
        node.child[i] = empty ? vkas::format::kEmptyRef : vkas::format::ChildRef(1);
    }
    return node;
}

TEST(packet_tests, group_test_keeps_every_child_a_ray_enters_and_lane_test_equals_the_ray_test) {
    const uint64_t seed = chooseSeed();
    std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
    Rng rng(seed);
    uint64_t entered = 0, kept = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        const bool negative[3] = {rng.coin(), rng.coin(), rng.coin()};
        const uint32_t count = 1 + rng.below(vkas::kPacketWidth);
        const std::vector<LaneRay> rays = randomPacket(rng, count, negative);
        const vkas::format::Node node = randomNode(rng, rays);
        std::vector<vkas::ShearedRay> sheared;
        float tMin[vkas::kPacketWidth] = {}, tMax[vkas::kPacketWidth] = {};
        float tMaxAll = -INFINITY;
        for (uint32_t l = 0; l < count; ++l) {
            sheared.push_back(rays[l].ray);
            tMin[l] = rays[l].tMin, tMax[l] = rays[l].tMax;
            tMaxAll = std::fmax(tMaxAll, tMax[l]);
        }
        const uint32_t lanes = (1u << count) - 1u;
        vkas::PacketLanes L;
        vkas::PacketFrustum f;
        ASSERT_TRUE(vkas::packetFrustum([&](uint32_t l) -> const vkas::ShearedRay& { return sheared[l]; }, lanes, tMin,
                                        L, f))
            << "trial " << trial;
        float groupEntry[vkas::format::kNodeWidth];
        const uint32_t group = vkas::packetChildEntries(node, f, tMaxAll, groupEntry);
        for (uint32_t i = 0; i < vkas::format::kNodeWidth; ++i) {
            uint32_t rayLanes = 0;
            for (uint32_t l = 0; l < count; ++l) {
                float entry[vkas::format::kNodeWidth];
                const uint32_t mask = vkas::childEntryDistances(node, rays[l].ray, tMin[l], tMax[l], entry);
                if (!((mask >> i) & 1u)) continue;
                rayLanes |= 1u << l;
                ++entered;
                ASSERT_TRUE((group >> i) & 1u) << "trial " << trial << ": child " << i << " entered by ray " << l
                                                << " at " << entry[i] << " but dropped by the group test";
                ASSERT_LE(groupEntry[i], entry[i]) << "trial " << trial << ": child " << i << ", ray " << l;
            }
            kept += (group >> i) & 1u;
            ASSERT_EQ(vkas::lanesEnteringChild(node, i, f, L, tMin, tMax, lanes), rayLanes)
                << "trial " << trial << ": child " << i;
        }
    }
    std::cout << entered << " (ray, child) entries, " << kept << " children kept by the group test" << std::endl;
    EXPECT_GT(entered, 10000u);  // the boxes do meet the rays
}

TEST(packet_tests, frustum_refuses_rays_without_one_octant) {
    vkas::ShearedRay r[2];
    const float o[3] = {0, 0, 0}, d0[3] = {1, 1, 1}, d1[3] = {1, -1, 1}, d2[3] = {1, 0, 1};
    vkas::prepareShearedRay(r[0], o, d0);
    vkas::prepareShearedRay(r[1], o, d1);
    const float tMin[vkas::kPacketWidth] = {};
    vkas::PacketLanes L;
    vkas::PacketFrustum f;
    const auto rayOf = [&](uint32_t l) -> const vkas::ShearedRay& { return r[l]; };
    EXPECT_FALSE(vkas::packetFrustum(rayOf, 3u, tMin, L, f)) << "two octants";
    EXPECT_TRUE(vkas::packetFrustum(rayOf, 1u, tMin, L, f)) << "one ray";
    vkas::prepareShearedRay(r[1], o, d2);
    EXPECT_FALSE(vkas::packetFrustum(rayOf, 3u, tMin, L, f)) << "a zero component";
}

// ---- tracePacket against traceKernel ----------------------------------------------------------------------------

// A triangle soup with duplicated triangles (some with the opposite winding): rays that meet them tie.
Mesh soupWithTies(Rng& rng) {
    Mesh m = triangleSoup(500, rng, 0.25f);
    const size_t n = m.triangleCount();
    for (size_t k = 0; k < 120; ++k) {
        const size_t t = rng.u32() % n;
        const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
        if (rng.coin())
            m.indices.insert(m.indices.end(), {a, b, c});
        else
            m.indices.insert(m.indices.end(), {a, c, b});
    }
    return m;
}

// An image's rays, row by row, from `eye` towards `target`.
std::vector<vkas::KernelRay> cameraRays(const float eye[3], const float target[3], uint32_t side, float halfWidth,
                                        uint32_t flags, uint32_t cullMask) {
    float fwd[3], right[3], up[3];
    for (int a = 0; a < 3; ++a) fwd[a] = target[a] - eye[a];
    const float len = std::sqrt(fwd[0] * fwd[0] + fwd[1] * fwd[1] + fwd[2] * fwd[2]);
    for (float& v : fwd) v /= len;
    right[0] = fwd[2], right[1] = 0, right[2] = -fwd[0];  // fwd x (0, 1, 0), up to sign
    up[0] = fwd[1] * right[2] - fwd[2] * right[1], up[1] = fwd[2] * right[0] - fwd[0] * right[2],
    up[2] = fwd[0] * right[1] - fwd[1] * right[0];
    std::vector<vkas::KernelRay> rays;
    for (uint32_t y = 0; y < side; ++y)
        for (uint32_t x = 0; x < side; ++x) {
            const float sx = halfWidth * (2.0f * (x + 0.5f) / side - 1.0f), sy = halfWidth * (1.0f - 2.0f * (y + 0.5f) / side);
            vkas::KernelRay r{};
            for (int a = 0; a < 3; ++a) r.origin[a] = eye[a], r.direction[a] = fwd[a] + sx * right[a] + sy * up[a];
            r.tMin = 0.0f;
            r.tMax = INFINITY;
            r.flags = flags;
            r.cullMask = cullMask;
            rays.push_back(r);
        }
    return rays;
}

bool sameHit(const vkas::QueryHit& a, const vkas::QueryHit& b) {
    if (a.type != b.type) return false;
    if (a.type == vkas::kCommittedNone) return std::bit_cast<uint32_t>(a.t) == std::bit_cast<uint32_t>(b.t);
    return std::bit_cast<uint32_t>(a.t) == std::bit_cast<uint32_t>(b.t) &&
           std::bit_cast<uint32_t>(a.barycentrics[0]) == std::bit_cast<uint32_t>(b.barycentrics[0]) &&
           std::bit_cast<uint32_t>(a.barycentrics[1]) == std::bit_cast<uint32_t>(b.barycentrics[1]) &&
           a.frontFace == b.frontFace && a.instance == b.instance && a.isTriangle == b.isTriangle &&
           a.triangleGeometryIndex == b.triangleGeometryIndex && a.trianglePrimitiveIndex == b.trianglePrimitiveIndex;
    // (The batch kernels fill only the fields a batch reports: batch_kernel.hpp, setReportedTriangleHit.)
}

std::string show(const vkas::QueryHit& h) {
    char s[160];
    std::snprintf(s, sizeof s, "type %u t %a instance %p geometry %u primitive %u bary %a %a front %d", h.type, h.t,
                  static_cast<const void*>(h.instance), h.isTriangle ? h.triangleGeometryIndex : 0,
                  h.isTriangle ? h.trianglePrimitiveIndex : 0, h.barycentrics[0], h.barycentrics[1], int(h.frontFace));
    return s;
}

class packets : public VkasTest, public ::testing::WithParamInterface<bool> {};

TEST_P(packets, each_ray_of_a_packet_gets_its_single_ray_hit) {
    const bool manyInstances = GetParam();
    auto soup = makeGeometry(soupWithTies(rng), VK_INDEX_TYPE_UINT32, rng.coin() ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0);
    auto knot = makeGeometry(torusKnot(96, 12), VK_INDEX_TYPE_UINT32, VK_GEOMETRY_OPAQUE_BIT_KHR);
    BuildOptions opt;
    AccelStruct* soupBlas = buildBlas(*soup, opt);
    AccelStruct* knotBlas = buildBlas(*knot, opt);
    std::vector<Instance> instances;
    const int count = manyInstances ? 16 : 1;
    constexpr uint32_t kInstanceFlags[] = {0, VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR,
                                           VK_GEOMETRY_INSTANCE_TRIANGLE_FLIP_FACING_BIT_KHR,
                                           VK_GEOMETRY_INSTANCE_FORCE_OPAQUE_BIT_KHR,
                                           VK_GEOMETRY_INSTANCE_FORCE_NO_OPAQUE_BIT_KHR};
    for (int i = 0; i < count; ++i) {
        Instance inst;
        if (count > 1) {
            inst.transform = randomTransform(rng, 0.5f, 1.5f, rng.coin(), 1.5f);
            inst.mask = rng.u32() & 0xFF;
            inst.flags = kInstanceFlags[rng.below(std::size(kInstanceFlags))];
        }
        inst.blas = i % 2 ? knotBlas : soupBlas;
        instances.push_back(inst);
    }
    AccelStruct* tlas = buildTlas(instances, opt);
    const std::byte* block = reinterpret_cast<const std::byte*>(tlas->data());

    constexpr uint32_t kFlagChoices[] = {0,
                                         VKAS_RAY_FLAG_OPAQUE,
                                         VKAS_RAY_FLAG_NO_OPAQUE,
                                         VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES,
                                         VKAS_RAY_FLAG_CULL_FRONT_FACING_TRIANGLES,
                                         VKAS_RAY_FLAG_CULL_OPAQUE,
                                         VKAS_RAY_FLAG_CULL_NO_OPAQUE,
                                         VKAS_RAY_FLAG_SKIP_TRIANGLES,
                                         VKAS_RAY_FLAG_NO_OPAQUE | VKAS_RAY_FLAG_CULL_BACK_FACING_TRIANGLES};
    auto scratch = std::make_unique<vkas::PacketScratch>();
    auto single = std::make_unique<vkas::KernelScratch>();
    uint64_t traced = 0, tied = 0, hits = 0, gaveUp = 0;
    for (int pass = 0; pass < 8; ++pass) {
        const uint32_t flags = pass < 2 ? 0u : kFlagChoices[rng.below(std::size(kFlagChoices))];
        const uint32_t cullMask = pass < 2 ? 0xFF : rng.u32() & 0xFF;
        // Outside the scene looking at it, and inside it with a wide view.
        const float outside[3] = {rng.uniformf(-1, 1), rng.uniformf(-1, 1), rng.uniformf(4, 6)};
        const float inside[3] = {rng.uniformf(-0.3f, 0.3f), rng.uniformf(-0.3f, 0.3f), rng.uniformf(-0.3f, 0.3f)};
        const float target[3] = {rng.uniformf(-0.2f, 0.2f), rng.uniformf(-0.2f, 0.2f), rng.uniformf(-0.2f, 0.2f)};
        const bool in = pass % 2 == 1;
        const auto rays = cameraRays(in ? inside : outside, target, 48, in ? 1.2f : 0.35f, flags, cullMask);
        for (size_t first = 0; first + vkas::kPacketWidth <= rays.size(); first += vkas::kPacketWidth) {
            vkas::QueryHit packetHits[vkas::kPacketWidth];
            uint32_t tiedLanes = 0;
            const vkas::KernelRay* packet = rays.data() + first;
            const bool octant = [&] {  // the caller's promise: one octant, no zero component
                for (uint32_t l = 0; l < vkas::kPacketWidth; ++l)
                    for (int a = 0; a < 3; ++a)
                        if (packet[l].direction[a] == 0.0f || (packet[l].direction[a] < 0) != (packet[0].direction[a] < 0))
                            return false;
                return true;
            }();
            if (!octant) continue;
            if (!vkas::tracePacket(block, vkas::resolveAccelerationStructure, packet, vkas::kPacketWidth, *scratch,
                                   packetHits, tiedLanes)) {
                ++gaveUp;  // over its budget of node tests: the caller traces these rays alone
                continue;
            }
            for (uint32_t l = 0; l < vkas::kPacketWidth; ++l) {
                vkas::QueryHit alone;
                ASSERT_TRUE(vkas::traceKernel(block, vkas::resolveAccelerationStructure, packet[l], *single, alone));
                if ((tiedLanes >> l) & 1u) {
                    ++tied;
                    continue;
                }
                ++traced;
                hits += alone.type != vkas::kCommittedNone;
                ASSERT_TRUE(sameHit(packetHits[l], alone))
                    << "pass " << pass << " flags 0x" << std::hex << flags << " mask 0x" << cullMask << std::dec
                    << " ray " << first + l << " (" << std::hexfloat << packet[l].origin[0] << " " << packet[l].origin[1]
                    << " " << packet[l].origin[2] << " / " << packet[l].direction[0] << " " << packet[l].direction[1]
                    << " " << packet[l].direction[2] << std::defaultfloat << "): packet " << show(packetHits[l])
                    << ", alone " << show(alone);
            }
        }
    }
    std::cout << traced << " rays compared, " << hits << " of them hits, " << tied << " tied (traced again alone), "
              << gaveUp << " packets given up" << std::endl;
    // Packets were traced: rays compared or tied (overlapping instances of the soup tie often: seed
    // 15673634899573118246 tied 5,283 rays and compared 6,653).
    EXPECT_GT(traced + tied, 8000u);
    EXPECT_GT(traced, 2000u);
    EXPECT_GT(hits, 1000u);
}

INSTANTIATE_TEST_SUITE_P(cpu, packets, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                             return std::string(info.param ? "instances" : "single");
                         });

TEST(packet_gather, coherent_runs_of_one_octant_become_packets) {
    std::vector<vkas::KernelRay> rays;
    const float eye[3] = {0, 0, 5}, target[3] = {0.1f, 0.2f, 0};
    rays = cameraRays(eye, target, 64, 0.05f, 0, 0xFF);  // 64 x 64 pixels, 0.0016 apart
    rays.resize(vkas::kMaxGather);                         // its first four rows
    vkas::KernelRay diffuse = rays[0];
    diffuse.direction[0] = 0.9f;  // far from its neighbours
    rays[5] = diffuse;
    rays[6].flags = VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT;  // never in a packet
    rays[7].direction[1] = 0.0f;                           // no octant
    std::vector<uint32_t> order(rays.size()), size(rays.size());
    const uint32_t groups = vkas::gatherPackets(rays.data(), uint32_t(rays.size()), vkas::PacketPolicy::Coherent,
                                                0.01f, order.data(), size.data());
    std::vector<int> seen(rays.size(), 0);
    uint32_t inPackets = 0;
    for (uint32_t g = 0, k = 0; g < groups; k += size[g++]) {
        ASSERT_GE(size[g], 1u);
        ASSERT_LE(size[g], vkas::kPacketWidth);
        for (uint32_t l = 0; l < size[g]; ++l) {
            ++seen[order[k + l]];
            if (size[g] > 1) {
                inPackets += 1;
                EXPECT_NE(order[k + l], 6u);
                EXPECT_NE(order[k + l], 7u);
                for (int a = 0; a < 3; ++a)
                    EXPECT_EQ(rays[order[k + l]].direction[a] < 0, rays[order[k]].direction[a] < 0);
            }
        }
    }
    for (size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(seen[i], 1) << "ray " << i;
    EXPECT_GT(inPackets, 200u);  // of 256: all but the rays named above and the rest of their packet
    // Scattered directions (bounces): traced one by one, in their own order.
    Rng rng(7);
    for (auto& r : rays)
        for (float& d : r.direction) d = rng.uniformf(-1, 1);
    const uint32_t scattered = vkas::gatherPackets(rays.data(), uint32_t(rays.size()), vkas::PacketPolicy::Coherent,
                                                   0.01f, order.data(), size.data());
    ASSERT_EQ(scattered, rays.size());
    for (uint32_t i = 0; i < scattered; ++i) EXPECT_EQ(order[i], i);
    const uint32_t off = vkas::gatherPackets(rays.data(), uint32_t(rays.size()), vkas::PacketPolicy::Off, 0.01f,
                                             order.data(), size.data());
    EXPECT_EQ(off, rays.size());
}

// The call-level chooser (packet_gather.hpp): a call whose first gathers form no packet stops gathering (its other
// tasks go alone), unless one of them formed a packet; fixed policies never change.
TEST(packet_chooser, stops_gathering_for_a_call_whose_first_gathers_form_no_packet) {
    using vkas::PacketChooser, vkas::PacketPolicy;
    PacketChooser incoherent(PacketPolicy::Coherent);
    for (int task = 0; task < 3; ++task) {
        EXPECT_EQ(incoherent.choice(), PacketChooser::Choice::Sample);
        incoherent.recordGather(0);
    }
    EXPECT_EQ(incoherent.choice(), PacketChooser::Choice::Sample);
    incoherent.recordGather(0);
    EXPECT_EQ(incoherent.choice(), PacketChooser::Choice::Alone);

    PacketChooser mixed(PacketPolicy::Coherent);
    mixed.recordGather(0);
    mixed.recordGather(5);  // a packet: the call keeps sampling
    for (int task = 0; task < 10; ++task) mixed.recordGather(0);
    EXPECT_EQ(mixed.choice(), PacketChooser::Choice::Sample);

    PacketChooser always(PacketPolicy::Always);
    for (int task = 0; task < 10; ++task) always.recordGather(0);
    EXPECT_EQ(always.choice(), PacketChooser::Choice::Packets);
}

}  // namespace
