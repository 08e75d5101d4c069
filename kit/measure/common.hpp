// Shared types of the vkas / Embree comparison (vkas_bench_embree): meshes, scenes, boxes, hits, timing and a
// parallel loop for the multi-threaded traversal runs.
#pragma once

#include <vkas/vkas.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

namespace vb {

// An indexed triangle mesh: float xyz positions (plus one padding float, so Embree may read 16 bytes at the last
// vertex), 32-bit indices.
struct Mesh {
    std::vector<float> vertices;
    std::vector<uint32_t> indices;
    size_t vertexCount() const { return vertices.size() / 3; }
    size_t triangleCount() const { return indices.size() / 3; }
};

using Transform = std::array<float, 12>;  // row-major 3x4, as VkTransformMatrixKHR and RTC_FORMAT_FLOAT3X4_ROW_MAJOR

// A benchmark scene: one mesh, traced directly (Embree) or through one identity instance (vkas needs a top
// level), or a many-instance scene: the mesh referenced by every transform in `instances`.
struct Scene {
    std::string name;
    std::string source;  // where the mesh came from
    Mesh mesh;
    std::vector<Transform> instances;
    bool thin = false;  // the long-thin-triangle scene of the FAST_TRACE target
    bool manyInstances() const { return !instances.empty(); }
};

struct Box {
    float lo[3] = {INFINITY, INFINITY, INFINITY};
    float hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    void grow(const float p[3]) {
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
    void grow(const Box& b) {
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], b.lo[k]), hi[k] = std::max(hi[k], b.hi[k]);
    }
    bool empty() const { return !(lo[0] <= hi[0]); }
    double area() const {
        if (empty()) return 0;
        const double dx = double(hi[0]) - lo[0], dy = double(hi[1]) - lo[1], dz = double(hi[2]) - lo[2];
        return 2 * (dx * dy + dy * dz + dz * dx);
    }
    double diagonal() const {
        if (empty()) return 0;
        return std::sqrt(std::pow(double(hi[0]) - lo[0], 2) + std::pow(double(hi[1]) - lo[1], 2) +
                         std::pow(double(hi[2]) - lo[2], 2));
    }
};

Box meshBounds(const Mesh& m);
Box transformBox(const Box& b, const Transform& x);
Box sceneBounds(const Scene& s);

// A closest or any hit, as both engines report it. prim < 0: a miss. inst: the instance (0 for a single mesh).
// geom: the geometry index (vkasTraceRays; -1 where not read: Embree, the ray-query loop).
struct Hit {
    int32_t inst = -1, prim = -1, geom = -1;
    float t = 0, u = 0, v = 0;
    bool hit() const { return prim >= 0; }
};

enum class RayKind { Camera, Diffuse, Shadow };
inline const char* rayKindName(RayKind k) {
    return k == RayKind::Camera ? "camera" : k == RayKind::Diffuse ? "diffuse" : "shadow";
}

inline double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Runs f(begin, end) over [0, count) in chunks on `threads` threads (the calling thread is one of them).
template <class F>
void parallelFor(unsigned threads, size_t count, size_t chunk, F&& f) {
    std::atomic<size_t> next{0};
    auto work = [&] {
        for (;;) {
            const size_t b = next.fetch_add(chunk);
            if (b >= count) return;
            f(b, std::min(count, b + chunk));
        }
    };
    std::vector<std::thread> pool;
    for (unsigned k = 1; k < threads; ++k) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
}

}  // namespace vb
