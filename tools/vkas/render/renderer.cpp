#include "renderer.hpp"

#include "camera_rays.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

namespace vkas_tool {
namespace {

double millisecondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void toArray(Vec3 v, float out[3]) { out[0] = v.x, out[1] = v.y, out[2] = v.z; }

// What the shader stage of a GPU renderer would reconstruct at a hit.
struct Surface {
    Vec3 position;
    Vec3 geometricNormal;  // facing the incoming ray
    Vec3 shadingNormal;    // interpolated vertex normal on the same side as geometricNormal
    Vec3 albedo;
};

// The object-space normal of a hit on a built-in primitive other than a triangle (spheres, swept spheres, boxes).
Vec3 primitiveNormal(const BlasDesc& blas, uint32_t prim, Vec3 p) {
    switch (blas.kind) {
    case PrimitiveKind::Spheres: return p - blas.spheres.at(prim).center;
    case PrimitiveKind::SweptSpheres: {
        // Find the segment, then the normal of the cone through its two spheres at the closest axis point,
        // tilted by the radius slope (exact on the cone, the caps are spheres).
        for (const SweptSphereChain& c : blas.chains) {
            if (prim >= c.segmentCount()) {
                prim -= c.segmentCount();
                continue;
            }
            const Vec3 a = c.points[prim], b = c.points[prim + 1];
            const float ra = c.radii[prim], rb = c.radii[prim + 1];
            const Vec3 axis = b - a;
            const float len2 = dot(axis, axis);
            float t = len2 > 0 ? dot(p - a, axis) / len2 : 0.0f;
            const Vec3 q = a + axis * std::clamp(t, 0.0f, 1.0f);
            Vec3 radial = p - q;
            if (t <= 0.0f || t >= 1.0f || len2 == 0.0f) return radial;  // a cap
            radial = normalize(radial - axis * (dot(radial, axis) / len2));
            // The tangent cone's normal leans towards the smaller sphere by the radius slope.
            const float len = std::sqrt(len2), dr = ra - rb;
            return radial * std::sqrt(std::max(len2 - dr * dr, 0.0f)) + axis * (dr / len);
        }
        return {0, 1, 0};
    }
    case PrimitiveKind::ProceduralBoxes: {
        const Box& bx = blas.boxes.at(prim);
        const Vec3 c = (bx.lo + bx.hi) * 0.5f, h = (bx.hi - bx.lo) * 0.5f;
        const Vec3 d{(p.x - c.x) / h.x, (p.y - c.y) / h.y, (p.z - c.z) / h.z};
        const Vec3 a{std::fabs(d.x), std::fabs(d.y), std::fabs(d.z)};
        if (a.x >= a.y && a.x >= a.z) return {d.x > 0 ? 1.0f : -1.0f, 0, 0};
        if (a.y >= a.z) return {0, d.y > 0 ? 1.0f : -1.0f, 0};
        return {0, 0, d.z > 0 ? 1.0f : -1.0f};
    }
    case PrimitiveKind::Triangles: break;
    }
    return {0, 1, 0};
}

Surface surfaceAt(const Scene& scene, const VkasRay& ray, const VkasHit& hit) {
    const InstanceDesc& inst = scene.instances.at(static_cast<size_t>(hit.instanceId));
    const BlasDesc& blas = scene.blases.at(inst.blas);
    Vec3 dir{ray.direction[0], ray.direction[1], ray.direction[2]};
    Surface s;
    s.position = Vec3{ray.origin[0], ray.origin[1], ray.origin[2]} + dir * hit.t;
    s.albedo = scene.materials.at(static_cast<size_t>(hit.instanceCustomIndex) % scene.materials.size()).albedo;
    const uint32_t prim = static_cast<uint32_t>(hit.primitiveIndex);
    if (blas.kind != PrimitiveKind::Triangles) {
        const Vec3 n = primitiveNormal(blas, prim, inst.transform.inverse().point(s.position));
        s.geometricNormal = normalize(inst.transform.normal(n));
        if (dot(s.geometricNormal, dir) > 0) s.geometricNormal = -s.geometricNormal;
        s.shadingNormal = s.geometricNormal;
        return s;
    }
    const GeometryDesc& geom = blas.geometries.at(static_cast<size_t>(hit.geometryIndex));
    const Mesh& mesh = *geom.mesh;
    const Affine toWorld = geom.transform ? inst.transform * *geom.transform : inst.transform;

    Vec3 w[3], n[3];
    for (uint32_t c = 0; c < 3; ++c) {
        uint32_t v = mesh.vertexIndex(prim, c);
        w[c] = toWorld.point(mesh.positions[v]);
        n[c] = mesh.normals[v];
    }
    s.geometricNormal = normalize(cross(w[1] - w[0], w[2] - w[0]));
    if (dot(s.geometricNormal, dir) > 0) s.geometricNormal = -s.geometricNormal;
    const float u = hit.barycentrics[0], v = hit.barycentrics[1];
    s.shadingNormal = normalize(toWorld.normal(n[0] * (1 - u - v) + n[1] * u + n[2] * v));
    if (dot(s.shadingNormal, s.geometricNormal) < 0) s.shadingNormal = -s.shadingNormal;
    return s;
}

// The renderer's intersection step for procedural boxes: where the object-space ray enters the crate.
VkBool32 VKAPI_PTR intersectCrate(void* user, const VkasAabbCandidate* c, float* tHit) {
    const Scene& scene = *static_cast<const Scene*>(user);
    const BlasDesc& blas = scene.blases.at(scene.instances.at(static_cast<size_t>(c->instanceId)).blas);
    const Box& bx = blas.boxes.at(static_cast<size_t>(c->primitiveIndex));
    const float lo[3] = {bx.lo.x, bx.lo.y, bx.lo.z}, hi[3] = {bx.hi.x, bx.hi.y, bx.hi.z};
    float tNear = c->tMin, tFar = c->tMax;
    for (int a = 0; a < 3; ++a) {
        const float inv = 1.0f / c->objectRayDirection[a];
        float t0 = (lo[a] - c->objectRayOrigin[a]) * inv, t1 = (hi[a] - c->objectRayOrigin[a]) * inv;
        if (t0 > t1) std::swap(t0, t1);
        tNear = std::max(tNear, t0);
        tFar = std::min(tFar, t1);
    }
    if (!(tNear <= tFar)) return VK_FALSE;
    *tHit = tNear;
    return VK_TRUE;
}

// Cosine-weighted direction around n.
Vec3 cosineSample(Vec3 n, float r1, float r2) {
    Vec3 a = std::fabs(n.x) > 0.9f ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
    Vec3 t = normalize(cross(a, n)), b = cross(n, t);
    float phi = 2.0f * std::numbers::pi_v<float> * r1, r = std::sqrt(r2);
    return normalize(t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * std::sqrt(std::max(0.0f, 1.0f - r2)));
}

Vec3 skyColour(Vec3 dir) {
    float h = std::clamp(dir.y, 0.0f, 1.0f);
    return Vec3{0.75f, 0.83f, 0.93f} * (1.0f - h) + Vec3{0.25f, 0.45f, 0.85f} * std::sqrt(h);
}

uint8_t toSrgb8(float linear) {
    linear = std::clamp(linear, 0.0f, 1.0f);
    float s = linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
    return static_cast<uint8_t>(std::lround(s * 255.0f));
}

void trace(VkContext& ctx, const Scene& scene, VkAccelerationStructureKHR tlas, VkasTraceMode mode,
           const std::vector<VkasRay>& rays, std::vector<VkasHit>& hits, double& ms) {
    hits.resize(rays.size());
    auto t0 = std::chrono::steady_clock::now();
    check(vkasTraceRaysProcedural(ctx.device(), tlas, mode, VKAS_RAY_FLAG_NONE, 0xFF,
                                  static_cast<uint32_t>(rays.size()), rays.data(), hits.data(), intersectCrate,
                                  const_cast<Scene*>(&scene)),
          "vkasTraceRaysProcedural");
    ms += millisecondsSince(t0);
}

}  // namespace

Image render(VkContext& ctx, const Scene& scene, VkAccelerationStructureKHR topLevel, const RenderOptions& options,
             RenderStats& stats) {
    auto start = std::chrono::steady_clock::now();
    const uint32_t W = options.width, H = options.height;
    const size_t pixels = static_cast<size_t>(W) * H;

    // Primary rays, one per pixel through its centre.
    const std::vector<VkasRay> primary = primaryRays(scene.camera, W, H, scene.rayTMax);
    std::vector<VkasHit> primaryHits;
    trace(ctx, scene, topLevel, VKAS_TRACE_MODE_CLOSEST_HIT, primary, primaryHits, stats.primaryMs);
    stats.primaryRays = pixels;

    // Occlusion rays in chunks of pixels, so that memory stays bounded whatever the sample count.
    Image image;
    image.width = W, image.height = H;
    image.rgb.resize(pixels * 3);
    const Vec3 sun = scene.sunDirection;
    const Vec3 sunColour{1.05f, 0.98f, 0.88f};
    const size_t chunk = std::max<size_t>(1, (1u << 20) / (options.aoSamples + 1));
    std::vector<Surface> surfaces;
    std::vector<VkasRay> rays;
    std::vector<VkasHit> hits;
    std::vector<int32_t> shadowRay;  // per pixel of the chunk: index of its shadow ray, or -1
    for (size_t begin = 0; begin < pixels; begin += chunk) {
        size_t end = std::min(pixels, begin + chunk);
        surfaces.clear();
        rays.clear();
        shadowRay.assign(end - begin, -1);
        for (size_t p = begin; p < end; ++p) {
            const VkasHit& hit = primaryHits[p];
            if (hit.type == VKAS_COMMITTED_INTERSECTION_NONE) {
                surfaces.push_back({});
                continue;
            }
            ++stats.primaryHits;
            Surface s = surfaceAt(scene, primary[p], hit);
            surfaces.push_back(s);
            float scale = std::max({1.0f, std::fabs(s.position.x), std::fabs(s.position.y), std::fabs(s.position.z)});
            Vec3 origin = s.position + s.geometricNormal * (2e-4f * scale);
            VkasRay r;
            toArray(origin, r.origin);
            r.tMin = 0.0f;
            if (dot(s.geometricNormal, sun) > 0 && dot(s.shadingNormal, sun) > 0) {
                shadowRay[p - begin] = static_cast<int32_t>(rays.size());
                toArray(sun, r.direction);
                r.tMax = scene.rayTMax;
                rays.push_back(r);
            }
            Rng rng(p, 3);
            for (uint32_t k = 0; k < options.aoSamples; ++k) {
                Vec3 d = cosineSample(s.shadingNormal, rng.uniform(), rng.uniform());
                float below = dot(d, s.geometricNormal);
                if (below <= 0) d = normalize(d - s.geometricNormal * (2.0f * below));
                toArray(d, r.direction);
                r.tMax = scene.aoRadius;
                rays.push_back(r);
            }
        }
        trace(ctx, scene, topLevel, VKAS_TRACE_MODE_ANY_HIT, rays, hits, stats.occlusionMs);
        stats.occlusionRays += rays.size();

        // Shade. AO rays of a pixel follow its shadow ray, in pixel order.
        size_t next = 0;
        for (size_t p = begin; p < end; ++p) {
            Vec3 colour;
            const VkasHit& hit = primaryHits[p];
            if (hit.type == VKAS_COMMITTED_INTERSECTION_NONE) {
                colour = skyColour({primary[p].direction[0], primary[p].direction[1], primary[p].direction[2]});
            } else {
                const Surface& s = surfaces[p - begin];
                float sunVisible = 0.0f;
                if (shadowRay[p - begin] >= 0) {
                    const VkasHit& h = hits[next++];
                    stats.occlusionHits += h.type != VKAS_COMMITTED_INTERSECTION_NONE;
                    sunVisible = h.type == VKAS_COMMITTED_INTERSECTION_NONE ? 1.0f : 0.0f;
                }
                uint32_t open = 0;
                for (uint32_t k = 0; k < options.aoSamples; ++k) {
                    const VkasHit& h = hits[next++];
                    stats.occlusionHits += h.type != VKAS_COMMITTED_INTERSECTION_NONE;
                    open += h.type == VKAS_COMMITTED_INTERSECTION_NONE;
                }
                float ao = options.aoSamples ? static_cast<float>(open) / options.aoSamples : 1.0f;
                Vec3 ambient = skyColour(s.shadingNormal) * (0.45f * ao);
                Vec3 direct = sunColour * (1.2f * sunVisible * std::max(0.0f, dot(s.shadingNormal, sun)));
                colour = mul(s.albedo, ambient + direct);
                // A little aerial perspective.
                float fog = 1.0f - std::exp(-hit.t * scene.fogDensity);
                colour = colour * (1.0f - fog) + Vec3{0.78f, 0.85f, 0.93f} * fog;
            }
            image.rgb[3 * p + 0] = toSrgb8(colour.x);
            image.rgb[3 * p + 1] = toSrgb8(colour.y);
            image.rgb[3 * p + 2] = toSrgb8(colour.z);
        }
        if (options.progress) options.progress(end, pixels);
    }
    stats.totalMs = millisecondsSince(start);
    return image;
}

}  // namespace vkas_tool
