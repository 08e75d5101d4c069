// CTS `format`: every vertex format x {nopadding, padded, minalign, unaligned} x index type x geometry transform,
// with primitiveOffset, firstVertex, a tight maxVertex and transformOffset. Traces against the oracle (which
// decodes the same bytes) and checks position fetch returns exactly the decoded (and transformed) positions.
#include <cmath>
#include <cstring>
#include <limits>

#include "meshes.hpp"

using namespace vt;

namespace {

enum class Layout { nopadding, padded, minalign, unaligned };
const char* layoutName(Layout l) {
    switch (l) {
        case Layout::nopadding: return "nopadding";
        case Layout::padded: return "padded";
        case Layout::minalign: return "minalign";
        case Layout::unaligned: return "unaligned";
    }
    return "?";
}
const char* indexName(VkIndexType t) {
    return t == VK_INDEX_TYPE_NONE_KHR ? "index_none" : t == VK_INDEX_TYPE_UINT16 ? "index_uint16" : "index_uint32";
}

struct FormatParam {
    oracle::FormatInfo format;
    Layout layout;
    VkIndexType indexType;
    bool transform;
};

std::string paramName(const ::testing::TestParamInfo<FormatParam>& info) {
    const auto& p = info.param;
    return std::string(p.format.name) + "_" + layoutName(p.layout) + "_" + indexName(p.indexType) +
           (p.transform ? "_transformed" : "_notransform");
}

std::vector<FormatParam> allParams() {
    std::vector<FormatParam> out;
    for (const auto& f : oracle::vertexFormats())
        for (Layout l : {Layout::nopadding, Layout::padded, Layout::minalign, Layout::unaligned})
            for (VkIndexType t : {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32})
                for (bool xf : {false, true}) out.push_back({f, l, t, xf});
    return out;
}

// Writes one vertex of `value` (coordinates in [-1, 1]; the packed UNORM format maps them to [0, 1]).
void encodeVertex(const oracle::FormatInfo& f, uint8_t* dst, const std::array<double, 3>& value, bool nanX,
                  bool minSnorm, bool floatExact, Rng& rng) {
    auto put = [&](auto v, uint32_t c) { std::memcpy(dst + c * f.componentSize, &v, sizeof v); };
    if (f.packed) {
        uint32_t w = 0;
        for (int c = 0; c < 3; ++c) {
            const uint32_t q = uint32_t(std::lround((value[c] + 1.0) / 2.0 * 1023.0)) & 0x3FF;
            w |= q << (10 * c);
        }
        w |= (rng.u32() & 3u) << 30;  // alpha: ignored
        std::memcpy(dst, &w, 4);
        return;
    }
    for (uint32_t c = 0; c < f.components; ++c) {
        const bool extra = c >= 3;  // the 4th component is ignored: random garbage
        double v = c < 3 ? value[c] : 0.0;
        switch (f.format) {
            case VK_FORMAT_R32G32_SFLOAT:
            case VK_FORMAT_R32G32B32_SFLOAT:
            case VK_FORMAT_R32G32B32A32_SFLOAT: {
                float x = float(v);
                if (extra) x = rng.coin(0.3) ? std::numeric_limits<float>::quiet_NaN() : rng.uniformf(-1e6f, 1e6f);
                if (c == 0 && nanX) x = std::numeric_limits<float>::quiet_NaN();
                put(x, c);
                break;
            }
            case VK_FORMAT_R16G16_SFLOAT:
            case VK_FORMAT_R16G16B16_SFLOAT:
            case VK_FORMAT_R16G16B16A16_SFLOAT: {
                uint16_t h = oracle::floatToHalf(float(v));
                if (extra) h = uint16_t(rng.u32());
                if (c == 0 && nanX) h = uint16_t(0x7E00 | (rng.u32() & 0x1FF) | 0x8000 * (rng.u32() & 1));
                put(h, c);
                break;
            }
            case VK_FORMAT_R16G16_SNORM:
            case VK_FORMAT_R16G16B16_SNORM:
            case VK_FORMAT_R16G16B16A16_SNORM: {
                int16_t s = int16_t(std::lround(std::clamp(v, -1.0, 1.0) * 32767.0));
                if (s == -32767 && minSnorm) s = -32768;
                if (extra) s = int16_t(rng.u32());
                put(s, c);
                break;
            }
            case VK_FORMAT_R8G8_SNORM:
            case VK_FORMAT_R8G8B8_SNORM:
            case VK_FORMAT_R8G8B8A8_SNORM: {
                int8_t s = int8_t(std::lround(std::clamp(v, -1.0, 1.0) * 127.0));
                if (s == -127 && minSnorm) s = -128;
                if (extra) s = int8_t(rng.u32());
                put(s, c);
                break;
            }
            case VK_FORMAT_R64G64_SFLOAT:
            case VK_FORMAT_R64G64B64_SFLOAT:
            case VK_FORMAT_R64G64B64A64_SFLOAT: {
                // Without a transform the value is not representable as float, so rounding is exercised.
                double x = floatExact ? double(float(v)) : v + rng.uniform(-1e-9, 1e-9);
                if (extra) x = rng.coin(0.3) ? std::numeric_limits<double>::quiet_NaN() : rng.uniform(-1e9, 1e9);
                if (c == 0 && nanX) x = std::numeric_limits<double>::quiet_NaN();
                put(x, c);
                break;
            }
            default: FAIL() << "unexpected format";
        }
    }
}

}  // namespace

class format : public VkasTest, public ::testing::WithParamInterface<FormatParam> {};

TEST_P(format, trace_and_position_fetch) {
    const FormatParam& P = GetParam();
    const oracle::FormatInfo& f = P.format;
    const bool indexed = P.indexType != VK_INDEX_TYPE_NONE_KHR;
    const uint32_t indexSize = P.indexType == VK_INDEX_TYPE_UINT16 ? 2 : 4;
    const uint32_t triCount = 24;
    const bool twoComponents = f.components == 2;
    VkFormatProperties props{};
    vkasGetFormatProperties(device, f.format, &props);
    ASSERT_TRUE(props.bufferFeatures & VK_FORMAT_FEATURE_ACCELERATION_STRUCTURE_VERTEX_BUFFER_BIT_KHR)
        << f.name << " must be reported as an acceleration-structure vertex format";

    // Vertex layout.
    uint64_t stride = f.size;
    uint64_t base = 0;
    switch (P.layout) {
        case Layout::nopadding: break;
        case Layout::padded: stride = f.size + f.componentSize * (1 + rng.below(3)); break;
        case Layout::minalign: base = f.componentSize; break;  // aligned to the component size only
        case Layout::unaligned: base = 1 + 2 * rng.below(3); stride = f.size + f.componentSize; break;
    }
    const uint32_t firstVertex = rng.below(5);
    const uint32_t primitiveOffset = indexed ? indexSize * rng.below(4) : f.componentSize * rng.below(4);

    // Triangles: random small triangles (coordinates in [-1, 1]); one triangle inactive for formats with NaN.
    std::vector<std::array<std::array<double, 3>, 3>> tris(triCount);
    for (auto& t : tris) {
        std::array<double, 3> c{rng.uniform(-0.7, 0.7), rng.uniform(-0.7, 0.7), twoComponents ? 0 : rng.uniform(-0.7, 0.7)};
        for (auto& v : t)
            for (int k = 0; k < 3; ++k) v[k] = (k == 2 && twoComponents) ? 0.0 : c[k] + rng.uniform(-0.3, 0.3);
    }
    // Make sure -1 (and the SNORM minimum) shows up.
    tris[1][0][0] = -1.0;
    const uint32_t nanTriangle = f.isFloat ? 2 + rng.below(triCount - 2) : ~0u;
    const uint32_t nanVertex = rng.below(3);

    // Vertex order in the buffer: indexed geometries use a shuffled pool plus unreferenced garbage vertices.
    std::vector<uint32_t> indices(3 * triCount);
    uint32_t vertexCount;
    if (indexed) {
        vertexCount = 3 * triCount + 5;
        std::vector<uint32_t> slots(vertexCount);
        for (uint32_t i = 0; i < vertexCount; ++i) slots[i] = i;
        std::shuffle(slots.begin(), slots.end(), rng.gen);
        for (uint32_t i = 0; i < 3 * triCount; ++i) indices[i] = slots[i];
        // maxVertex must be tight: make sure the last slot is referenced.
        indices[3 * triCount - 1] = vertexCount - 1;
        for (uint32_t i = 0; i + 1 < 3 * triCount; ++i)
            if (indices[i] == vertexCount - 1) indices[i] = slots[3 * triCount - 1];
    } else {
        vertexCount = 3 * triCount;
        for (uint32_t i = 0; i < 3 * triCount; ++i) indices[i] = i;
    }
    const uint32_t maxVertex = firstVertex + vertexCount - 1;
    const uint64_t vertexBase = base + (indexed ? 0 : primitiveOffset);
    // The buffer ends exactly after the last vertex's bytes (no stride padding after it).
    std::vector<uint8_t> vertexBuffer(vertexBase + stride * maxVertex + f.size, 0xAA);
    for (uint32_t i = 0; i < 3 * triCount; ++i) {
        const uint32_t tri = i / 3, corner = i % 3;
        uint8_t* dst = vertexBuffer.data() + vertexBase + stride * (uint64_t(indices[i]) + firstVertex);
        encodeVertex(f, dst, tris[tri][corner], tri == nanTriangle && corner == nanVertex, tri == 1 && corner == 0,
                     P.transform, rng);
        if (HasFatalFailure()) return;
    }
    if (indexed) {  // unreferenced pool vertices: valid random data
        for (uint32_t v = 0; v < vertexCount; ++v)
            if (std::find(indices.begin(), indices.end(), v) == indices.end())
                encodeVertex(f, vertexBuffer.data() + vertexBase + stride * (uint64_t(v) + firstVertex),
                             {rng.uniform(-1, 1), rng.uniform(-1, 1), 0.0}, false, false, P.transform, rng);
    }

    std::vector<uint8_t> indexBuffer;
    const uint64_t indexBase = P.layout == Layout::unaligned ? 1 : 0;
    if (indexed) {
        indexBuffer.assign(indexBase + primitiveOffset + indexSize * 3 * triCount, 0xAA);
        for (uint32_t i = 0; i < 3 * triCount; ++i) {
            uint8_t* dst = indexBuffer.data() + indexBase + primitiveOffset + indexSize * i;
            if (indexSize == 2) {
                const uint16_t v = uint16_t(indices[i]);
                std::memcpy(dst, &v, 2);
            } else {
                std::memcpy(dst, &indices[i], 4);
            }
        }
    }
    std::vector<uint8_t> transformBuffer;
    const uint32_t transformOffset = 16 * rng.below(3);
    VkTransformMatrixKHR m = identityTransform();
    if (P.transform) {
        const uint64_t tb = P.layout == Layout::unaligned ? 3 : 0;
        transformBuffer.assign(tb + transformOffset + 48, 0xAA);
        m = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 1.0f);
        std::memcpy(transformBuffer.data() + tb + transformOffset, &m, 48);
    }

    VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    auto& td = g.geometry.triangles;
    td.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    td.vertexFormat = f.format;
    td.vertexData.hostAddress = vertexBuffer.data() + base;
    td.vertexStride = stride;
    td.maxVertex = maxVertex;
    td.indexType = P.indexType;
    if (indexed) td.indexData.hostAddress = indexBuffer.data() + indexBase;
    if (P.transform) td.transformData.hostAddress = transformBuffer.data() + (P.layout == Layout::unaligned ? 3 : 0);
    VkAccelerationStructureBuildRangeInfoKHR range{triCount, primitiveOffset, firstVertex, transformOffset};

    BuildOptions opt;
    opt.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR;
    AccelStruct* blas = buildBlas({g}, {range}, opt);
    // The oracle read the same bytes; sanity-check its view (the test's own encoding).
    ASSERT_EQ(blas->blas->geometries.size(), 1u);
    for (uint32_t i = 0; i < triCount; ++i)
        EXPECT_EQ(blas->blas->geometries[0].triangles[i].active, i != nanTriangle) << "triangle " << i;

    Instance inst;
    inst.transform = randomTransform(rng, 0.5f, 2.0f, rng.coin(), 2.0f);
    inst.blas = blas;
    AccelStruct* tlas = buildTlas({inst});
    const oracle::Scene& scene = *tlas->scene;

    auto rays = targetedRays(scene, 64);
    const auto more = randomRays(scene, 64);
    rays.insert(rays.end(), more.begin(), more.end());
    const size_t hits = checkRays(tlas, rays);
    EXPECT_GT(hits, rays.size() / 4) << "most targeted rays should hit";

    // Position fetch: committed and candidate positions are exactly the decoded (+transformed) vertices.
    const auto& oracleTris = blas->blas->geometries[0].triangles;
    auto checkPositions = [&](const VkasRayQuery& q, bool committed, const oracle::Ray& ray) {
        const int32_t prim = vkasRayQueryGetIntersectionPrimitiveIndex(&q, committed ? VK_TRUE : VK_FALSE);
        ASSERT_GE(prim, 0);
        ASSERT_LT(uint32_t(prim), triCount);
        float pos[3][3];
        std::memset(pos, 0xAA, sizeof pos);
        vkasRayQueryGetIntersectionTriangleVertexPositions(&q, committed ? VK_TRUE : VK_FALSE, pos);
        for (int v = 0; v < 3; ++v)
            for (int k = 0; k < 3; ++k) {
                // Without a transform the decoded value must be exact. With one, the spec does not say whether the
                // decoded value is rounded to float before the (double) transform: allow that rounding.
                double tol = 0;
                if (P.transform) {
                    double mag = std::fabs(m.matrix[k][3]);
                    for (int j = 0; j < 3; ++j) mag += std::fabs(m.matrix[k][j]) * 1.5;  // |decoded| <= 1.5
                    tol = std::ldexp(mag, -22);
                }
                EXPECT_LE(std::fabs(double(pos[v][k]) - oracleTris[prim].v[v][k]), tol)
                    << "primitive " << prim << " vertex " << v << " component " << k << (committed ? " committed" : " candidate")
                    << "\n  vkas " << pos[v][k] << " expected " << oracleTris[prim].v[v][k] << "\n  ray " << describe(ray)
                    << "\n  seed " << seed;
            }
    };
    for (const auto& ray : rays) {
        VkasRayQuery q;
        vkasRayQueryInitialize(&q, tlas->handle, 0, 0xFF, ray.origin.data(), ray.tMin, ray.direction.data(), ray.tMax);
        while (vkasRayQueryProceed(&q)) {
            checkPositions(q, false, ray);
            vkasRayQueryConfirmIntersection(&q);
        }
        if (vkasRayQueryGetIntersectionType(&q, VK_TRUE) == VKAS_COMMITTED_INTERSECTION_TRIANGLE) checkPositions(q, true, ray);
        if (HasFailure()) break;
    }
}

INSTANTIATE_TEST_SUITE_P(cpu_built, format, ::testing::ValuesIn(allParams()), paramName);
