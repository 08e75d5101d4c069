// Engine-level: the triangle fetch specialised per geometry (TriangleSource::visit / fetchAs, used by builds and
// refits) against the general decode it replaced (decodeVertex for every vertex, the geometry transform in
// double, one rounding to float), bit for bit, for every supported vertex format, index type NONE / UINT16 /
// UINT32, with and without a transform, firstVertex and primitiveOffset, odd strides and unaligned buffers, on
// random vertex bytes that include NaNs (quiet and signalling), infinities, subnormals and signed zeros. Also the
// inline degeneracy test against a direct evaluation. Random inputs; the seed is printed (VKAS_TEST_SEED replays).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <iostream>
#include <random>
#include <vector>

#include "engine/input/triangles.hpp"
#include "engine/util/math.hpp"
#include "engine/input/vertex_format.hpp"
#include "vkas_test.hpp"

namespace {

using namespace vkas;

// Random bytes for one component of `size` bytes, biased towards special values for float formats.
void randomComponent(vt::Rng& rng, VkFormat format, uint32_t componentSize, uint8_t* out) {
    const bool isFloat = format == VK_FORMAT_R32G32_SFLOAT || format == VK_FORMAT_R32G32B32_SFLOAT ||
                         format == VK_FORMAT_R32G32B32A32_SFLOAT || format == VK_FORMAT_R16G16_SFLOAT ||
                         format == VK_FORMAT_R16G16B16_SFLOAT || format == VK_FORMAT_R16G16B16A16_SFLOAT ||
                         format == VK_FORMAT_R64G64_SFLOAT || format == VK_FORMAT_R64G64B64_SFLOAT ||
                         format == VK_FORMAT_R64G64B64A64_SFLOAT;
    if (!isFloat || rng.coin(0.3)) {  // raw bits
        for (uint32_t b = 0; b < componentSize; ++b) out[b] = uint8_t(rng.u32());
        return;
    }
    const uint32_t pick = rng.below(10);
    if (componentSize == 4) {
        const uint32_t specials[] = {0x7FC00000u, 0x7F800001u, 0xFFA00005u, 0x7F800000u, 0xFF800000u,
                                     0x00000001u, 0x80000000u, 0x00000000u};
        uint32_t bits;
        if (pick < 8) bits = specials[pick];
        else {
            const float f = rng.uniformf(-4.0f, 4.0f);
            std::memcpy(&bits, &f, 4);
        }
        std::memcpy(out, &bits, 4);
    } else if (componentSize == 2) {
        const uint16_t specials[] = {0x7E00, 0x7C01, 0xFC00, 0x7C00, 0x0001, 0x8000, 0x0000, 0x3C00};
        uint16_t bits = pick < 8 ? specials[pick] : uint16_t(rng.u32() & 0x7BFF);
        std::memcpy(out, &bits, 2);
    } else {
        const uint64_t specials[] = {0x7FF8000000000000ull, 0x7FF0000000000001ull, 0x7FF0000000000000ull,
                                     0x0000000000000001ull, 0x8000000000000000ull, 0x47EFFFFFF0000000ull,
                                     0x3690000000000000ull, 0x3FF0000000000000ull};
        uint64_t bits;
        if (pick < 8) bits = specials[pick];
        else {
            const double d = rng.uniform(-4.0, 4.0);
            std::memcpy(&bits, &d, 8);
        }
        std::memcpy(out, &bits, 8);
    }
}

// Bit for bit, except that any NaN equals any NaN: which operand's payload a NaN sum carries follows the operand
// order, which the optimizer may choose (at -O3 the transform's sums of a signalling and a quiet NaN came out with the
// other payload), and the format promises a NaN, not its payload.
bool samePositions(const float (&a)[3][3], const float (&b)[3][3]) {
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) {
            if (std::isnan(a[k][c]) && std::isnan(b[k][c])) continue;
            if (std::memcmp(&a[k][c], &b[k][c], 4) != 0) return false;
        }
    return true;
}

// The general fetch: what TriangleSource::fetch computed before it was specialised.
bool referenceFetch(const VkAccelerationStructureGeometryTrianglesDataKHR& t,
                    const VkAccelerationStructureBuildRangeInfoKHR& r, uint32_t i, float v[3][3]) {
    const auto* vb = static_cast<const std::byte*>(t.vertexData.hostAddress);
    const auto* ib = static_cast<const std::byte*>(t.indexData.hostAddress);
    Affine3x4d m{};
    if (t.transformData.hostAddress) {
        float f[3][4];
        std::memcpy(f, static_cast<const std::byte*>(t.transformData.hostAddress) + r.transformOffset, sizeof f);
        m = affineFromFloat(f);
    }
    bool active = true;
    for (uint32_t j = 0; j < 3; ++j) {
        const uint64_t k = 3ull * i + j;
        const std::byte* p;
        if (t.indexType == VK_INDEX_TYPE_NONE_KHR) {
            p = vb + r.primitiveOffset + t.vertexStride * (r.firstVertex + k);
        } else {
            uint64_t index;
            if (t.indexType == VK_INDEX_TYPE_UINT16) index = loadUnaligned<uint16_t>(ib + r.primitiveOffset + 2 * k);
            else index = loadUnaligned<uint32_t>(ib + r.primitiveOffset + 4 * k);
            p = vb + t.vertexStride * (r.firstVertex + index);
        }
        double d[3];
        decodeVertex(t.vertexFormat, p, d);
        if (std::isnan(d[0])) active = false;
        double q[3];
        if (t.transformData.hostAddress) applyAffine(m, d, q);
        else std::memcpy(q, d, sizeof q);
        for (int c = 0; c < 3; ++c) v[j][c] = float(q[c]);
    }
    return active;
}

class geometry_fetch : public ::testing::Test {
  protected:
    void SetUp() override {
        seed = vt::chooseSeed();
        rng = vt::Rng(seed);
        std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
    }
    void TearDown() override {
        if (HasFailure()) std::cout << "[   SEED   ] replay with VKAS_TEST_SEED=" << seed << std::endl;
    }
    uint64_t seed = 0;
    vt::Rng rng;
};

TEST_F(geometry_fetch, specialised_fetch_matches_general_decode) {
    uint64_t compared = 0, inactive = 0;
    for (uint32_t f = 0; f < kSupportedVertexFormatCount; ++f) {
        const VkFormat format = kSupportedVertexFormats[f];
        const VertexFormatInfo* fi = vertexFormatInfo(format);
        ASSERT_NE(fi, nullptr);
        for (VkIndexType it : {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32})
            for (int transformed = 0; transformed < 2; ++transformed) {
                SCOPED_TRACE(testing::Message() << "format " << format << " index " << it << " transform " << transformed);
                const uint32_t primitives = 50 + rng.below(100), vertices = 40 + rng.below(60);
                const uint32_t stride = fi->size + fi->componentSize * rng.below(3);
                const uint32_t firstVertex = rng.below(4), primitiveOffset = 4 * rng.below(4);
                const uint32_t needed = it == VK_INDEX_TYPE_NONE_KHR ? 3 * primitives : vertices;
                // One byte of misalignment: host pointers need none.
                std::vector<uint8_t> vbytes(1 + primitiveOffset + size_t(stride) * (firstVertex + needed), 0xAA);
                uint8_t* vb = vbytes.data() + 1;
                const uint32_t components = fi->packed ? 1 : fi->size / fi->componentSize;
                for (uint32_t n = 0; n < firstVertex + needed; ++n) {
                    uint8_t* p = vb + (it == VK_INDEX_TYPE_NONE_KHR ? primitiveOffset : 0) + size_t(stride) * n;
                    for (uint32_t c = 0; c < components; ++c)
                        randomComponent(rng, format, fi->packed ? 4 : fi->componentSize, p + c * fi->componentSize);
                }
                const uint32_t isize = it == VK_INDEX_TYPE_UINT16 ? 2 : 4;
                std::vector<uint8_t> ibytes(1 + primitiveOffset + size_t(isize) * 3 * primitives + 4, 0xAA);
                uint8_t* ib = ibytes.data() + 1;
                for (uint32_t k = 0; k < 3 * primitives; ++k) {
                    // Repeated indices make degenerate triangles.
                    const uint32_t index = rng.coin(0.1) && k % 3 ? rng.below(3) : rng.below(vertices);
                    std::memcpy(ib + primitiveOffset + isize * k, &index, isize);
                }
                float m[3][4];
                for (auto& row : m)
                    for (float& x : row) x = rng.uniformf(-2.0f, 2.0f);
                std::vector<uint8_t> tbytes(8 + sizeof m);
                std::memcpy(tbytes.data() + 8, m, sizeof m);
                VkAccelerationStructureGeometryTrianglesDataKHR t{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR};
                t.vertexFormat = format;
                t.vertexData.hostAddress = vb;
                t.vertexStride = stride;
                t.maxVertex = firstVertex + needed;
                t.indexType = it;
                t.indexData.hostAddress = it == VK_INDEX_TYPE_NONE_KHR ? nullptr : ib;
                t.transformData.hostAddress = transformed ? tbytes.data() : nullptr;
                VkAccelerationStructureBuildRangeInfoKHR r{primitives, primitiveOffset, firstVertex, transformed ? 8u : 0u};
                const TriangleSource source(t, r);
                for (uint32_t i = 0; i < primitives; ++i) {
                    float want[3][3], got[3][3], typed[3][3];
                    const bool a = referenceFetch(t, r, i, want);
                    const bool b = source.fetch(i, got);
                    const bool c = source.visit([&](auto reader) { return reader.fetch(i, typed); });
                    ASSERT_EQ(a, b) << "primitive " << i;
                    ASSERT_EQ(a, c) << "primitive " << i;
                    ASSERT_TRUE(samePositions(want, got)) << "primitive " << i;
                    ASSERT_TRUE(samePositions(want, typed)) << "primitive " << i;
                    ++compared, inactive += !a;
                }
            }
    }
    EXPECT_GT(inactive, 0u);
    std::cout << compared << " triangles compared, " << inactive << " inactive" << std::endl;
}

// The inline degeneracy test is the double cross product of the float edge vectors, exactly zero.
TEST_F(geometry_fetch, degeneracy) {
    for (int n = 0; n < 20000; ++n) {
        float v[3][3];
        for (auto& p : v)
            for (float& c : p) c = rng.coin(0.3) ? float(rng.below(5)) : rng.uniformf(-3.0f, 3.0f);
        if (rng.coin(0.3))  // collinear: v2 = v0 + s (v1 - v0) with s a power of two, exact in float
            for (int c = 0; c < 3; ++c) v[2][c] = v[0][c] + 2.0f * (v[1][c] - v[0][c]);
        if (rng.coin(0.1)) std::memcpy(v[1], v[0], sizeof v[0]);
        long double e1[3], e2[3];
        for (int c = 0; c < 3; ++c) e1[c] = (long double)v[1][c] - v[0][c], e2[c] = (long double)v[2][c] - v[0][c];
        const bool exact = e1[1] * e2[2] == e1[2] * e2[1] && e1[2] * e2[0] == e1[0] * e2[2] && e1[0] * e2[1] == e1[1] * e2[0];
        ASSERT_EQ(isDegenerateTriangle(v), exact) << n;
    }
}

}  // namespace
