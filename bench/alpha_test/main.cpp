// vkas_bench_alpha: alpha-tested geometry (issue 16, VK_EXT_opacity_micromap). A foliage-like scene (many large
// quads, randomly placed and oriented, sharing a few leaf-shaped alpha patterns) traced
//   1. by vkas with a 2-state opacity micromap (vkasTraceRays: transparent micro-triangles ignored by traversal),
//   2. by vkas without micromap, the geometry non-opaque, through the ray-query functions: every triangle candidate
//      alpha-tested by the application and confirmed if opaque,
//   3. by Embree 3 with intersection / occlusion filter functions doing the same alpha test,
//   4. by vkas with a coarser 4-state micromap (unknown states on the leaves' outlines) and the ray-query loop
//      confirming the remaining non-opaque candidates with the exact alpha test.
// The alpha pattern is defined exactly at micro-triangle resolution (micromap_index.hpp), so every variant must give
// the same hits; the program counts the rays that differ. Camera rays, random rays (closest hit) and random segments
// (any hit), 1 thread and all threads, medians of --reps runs. See docs/PERFORMANCE.md, "Opacity micromaps".
#include "micromap_index.hpp"

#include <vkas/vkas.h>

#include "device_commands.hpp"  // kit/

#include <embree3/rtcore.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

// ----------------------------------------------------------------------------------------------------------------
// Options
// ----------------------------------------------------------------------------------------------------------------

struct Options {
    uint32_t quads = 50000;
    uint32_t patterns = 4;  // distinct leaf patterns (each quad uses pattern quad % patterns)
    uint32_t level = 8;     // subdivision level of the exact alpha (2-state micromap)
    uint32_t level4 = 6;    // subdivision level of the 4-state micromap (unknown where the level-`level` states mix)
    float size = 2.5f;      // largest half-extent of a quad; the volume is [-50, 50]^3
    size_t rays = 262144;   // per ray kind
    int reps = 5;
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    uint64_t seed = 1;
    bool embreeRobust = true;
    bool validate = false;
    bool noEmbree = false;
    size_t showDifferences = 0;  // print the first N differing rays of each variant
    std::string json;
};

[[noreturn]] void usage(const char* msg) {
    if (msg) std::fprintf(stderr, "vkas_bench_alpha: %s\n", msg);
    std::fprintf(stderr,
                 "usage: vkas_bench_alpha [--quads N] [--patterns K] [--level L] [--level4 L4] [--size S] [--rays N]\n"
                 "                        [--reps R] [--threads N] [--seed S] [--embree-flags robust|none]\n"
                 "                        [--validate] [--no-embree] [--quick] [--show-differences N] [--json FILE]\n");
    std::exit(2);
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) usage(("missing value after " + a).c_str());
            return argv[++i];
        };
        auto num = [&]() -> uint64_t {
            const std::string s = next();
            char* end = nullptr;
            const unsigned long long v = std::strtoull(s.c_str(), &end, 10);
            if (s.empty() || *end) usage(("not a number: " + s).c_str());
            return v;
        };
        if (a == "--quads") o.quads = uint32_t(num());
        else if (a == "--patterns") o.patterns = uint32_t(num());
        else if (a == "--level") o.level = uint32_t(num());
        else if (a == "--level4") o.level4 = uint32_t(num());
        else if (a == "--size") o.size = std::strtof(next().c_str(), nullptr);
        else if (a == "--rays") o.rays = size_t(num());
        else if (a == "--reps") o.reps = int(num());
        else if (a == "--threads") o.threads = unsigned(num());
        else if (a == "--seed") o.seed = num();
        else if (a == "--embree-flags") {
            const std::string f = next();
            if (f != "robust" && f != "none") usage("--embree-flags takes robust or none");
            o.embreeRobust = f == "robust";
        } else if (a == "--validate") o.validate = true;
        else if (a == "--no-embree") o.noEmbree = true;
        else if (a == "--quick") o.quads = 10000, o.rays = 16384, o.reps = 1;
        else if (a == "--json") o.json = next();
        else if (a == "--show-differences") o.showDifferences = size_t(num());
        else if (a == "--help" || a == "-h") usage(nullptr);
        else usage(("unknown option " + a).c_str());
    }
    if (o.quads == 0 || o.patterns == 0 || o.rays == 0 || o.reps < 1 || o.threads == 0) usage("counts must be positive");
    if (o.level < 1 || o.level > 12 || o.level4 < 1 || o.level4 > o.level) usage("need 1 <= --level4 <= --level <= 12");
    if (!(o.size > 0)) usage("--size must be positive");
    return o;
}

double msSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The calling thread's CPU time: on a shared machine, the 1-thread runs are also rated by it (every 1-thread
// variant runs on the calling thread alone), which leaves out the time other processes take the core.
double threadCpuMs() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}
double gCpuMs = 0;  // the calling thread's CPU time in the last trace call's timed part

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Runs f(begin, end) over [0, count) in chunks on `threads` threads (the calling thread is one of them): the
// threading of the ray-query and Embree variants, the same as vkasTraceRays's worker count.
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
constexpr size_t kChunk = 1024;

// ----------------------------------------------------------------------------------------------------------------
// The scene: quads with leaf-shaped alpha, defined at micro-triangle resolution
// ----------------------------------------------------------------------------------------------------------------

constexpr float kHalf = 50.0f;  // the volume [-kHalf, kHalf]^3

struct Scene {
    uint32_t quads = 0, patterns = 0, level = 0, level4 = 0;
    std::vector<float> vertices;    // xyz per vertex, plus one padding float (Embree reads 16 bytes at a vertex)
    std::vector<uint32_t> indices;  // 3 per triangle; triangle 2q is (v0, v1, v2) of quad q, 2q + 1 is (v0, v2, v3)
    std::vector<uint32_t> ommIndex;  // per triangle: its micromap triangle, 2 * pattern + (triangle & 1)
    std::vector<uint8_t> states2;    // 2 * patterns micromap triangles at `level`, 2-state
    std::vector<uint8_t> states4;    // the same at `level4`, 4-state (2 or 3 where the fine states mix)
    double opaqueFraction = 0;       // of the micro-triangles (area)
    double unknownFraction = 0;      // of the 4-state micro-triangles
    size_t hierarchyMismatches = 0;  // fine micro-triangles whose coarse index is not fine >> 2 (level - level4)
    uint32_t triangles() const { return 2 * quads; }
    uint32_t vertexCount() const { return 4 * quads; }
    // The application's alpha test: the state of the micro-triangle that (u, v) selects on triangle `prim`.
    bool opaque(uint32_t prim, float u, float v) const {
        const uint8_t* data = &states2[size_t(ommIndex[prim]) * alpha::bytes2(level)];
        return alpha::state2(data, alpha::microTriangleIndex(u, v, level)) != 0;
    }
};

uint32_t hash32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352dU;
    x ^= x >> 15;
    x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

// Leaf pattern k at quad coordinates (x, y) in [0, 1]^2: a blade along x with holes (cells of 1/16 of the quad,
// about 30% of them cut out). About 40% of the quad is opaque.
bool leaf(uint32_t k, float x, float y) {
    const float p = 0.55f + 0.1f * float(k % 4);
    const float w = 0.42f * std::pow(std::max(0.0f, std::sin(float(M_PI) * x)), p);
    const float bend = 0.06f * float(int(k % 3) - 1) * std::sin(float(M_PI) * x);
    if (std::fabs(y - 0.5f - bend) >= w) return false;
    const uint32_t cx = std::min(15u, uint32_t(x * 16)), cy = std::min(15u, uint32_t(y * 16));
    return hash32(k * 7919u + cx * 16u + cy + 12345u) % 100u >= 30u;
}

Scene makeScene(const Options& o) {
    Scene s;
    s.quads = o.quads, s.patterns = o.patterns, s.level = o.level, s.level4 = o.level4;
    std::mt19937_64 rng(o.seed);
    std::uniform_real_distribution<float> uni(-1.0f, 1.0f), ext(0.5f, 1.0f), angle(0.0f, 2.0f * float(M_PI));
    std::normal_distribution<float> gauss;
    s.vertices.reserve(12 * size_t(o.quads) + 1);
    for (uint32_t q = 0; q < o.quads; ++q) {
        const float c[3] = {kHalf * uni(rng), kHalf * uni(rng), kHalf * uni(rng)};
        float n[3] = {gauss(rng), gauss(rng), gauss(rng)};
        const float nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) + 1e-30f;
        for (float& x : n) x /= nl;
        // t0, s0: a basis of the plane; rotated by a random angle
        float t0[3] = {std::fabs(n[0]) < 0.9f ? 1.0f : 0.0f, std::fabs(n[0]) < 0.9f ? 0.0f : 1.0f, 0.0f};
        const float d = t0[0] * n[0] + t0[1] * n[1] + t0[2] * n[2];
        for (int k = 0; k < 3; ++k) t0[k] -= d * n[k];
        const float tl = std::sqrt(t0[0] * t0[0] + t0[1] * t0[1] + t0[2] * t0[2]);
        for (float& x : t0) x /= tl;
        const float s0[3] = {n[1] * t0[2] - n[2] * t0[1], n[2] * t0[0] - n[0] * t0[2], n[0] * t0[1] - n[1] * t0[0]};
        const float phi = angle(rng), cp = std::cos(phi), sp = std::sin(phi);
        const float a = o.size * ext(rng), b = o.size * ext(rng);
        float t[3], sv[3];
        for (int k = 0; k < 3; ++k) t[k] = a * (cp * t0[k] + sp * s0[k]), sv[k] = b * (-sp * t0[k] + cp * s0[k]);
        const float corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (const auto& cc : corner)
            for (int k = 0; k < 3; ++k) s.vertices.push_back(c[k] + cc[0] * t[k] + cc[1] * sv[k]);
        const uint32_t v0 = 4 * q;
        for (uint32_t i : {v0, v0 + 1, v0 + 2, v0, v0 + 2, v0 + 3}) s.indices.push_back(i);
        const uint32_t k = q % o.patterns;
        s.ommIndex.push_back(2 * k), s.ommIndex.push_back(2 * k + 1);
    }
    s.vertices.push_back(0.0f);

    // The micromap triangles: pattern k, triangle j, sampled at the centroid of every micro-triangle. Quad coordinates:
    // triangle 0 (v0, v1, v2): x = u + v, y = v; triangle 1 (v0, v2, v3): x = u, y = u + v.
    const std::vector<alpha::Centroid> fine = alpha::microTriangleCentroids(o.level);
    const uint32_t nFine = 1u << (2 * o.level), nCoarse = 1u << (2 * o.level4);
    if (fine.size() != nFine) throw std::logic_error("micro-triangle count");
    const uint32_t b2 = alpha::bytes2(o.level), b4 = alpha::bytes4(o.level4);
    s.states2.assign(size_t(2) * o.patterns * b2, 0);
    s.states4.assign(size_t(2) * o.patterns * b4, 0);
    size_t opaque = 0, unknown = 0;
    std::vector<uint32_t> coarseOpaque(nCoarse), coarseTotal(nCoarse);
    std::vector<uint8_t> seen(nFine);
    for (uint32_t m = 0; m < 2 * o.patterns; ++m) {
        uint8_t* d2 = &s.states2[size_t(m) * b2];
        std::fill(seen.begin(), seen.end(), 0);
        std::fill(coarseOpaque.begin(), coarseOpaque.end(), 0);
        std::fill(coarseTotal.begin(), coarseTotal.end(), 0);
        for (const alpha::Centroid& c : fine) {
            const uint32_t idx = alpha::microTriangleIndex(c.u, c.v, o.level);
            if (idx >= nFine || seen[idx]++) throw std::logic_error("the barycentrics-to-index mapping is not a bijection");
            const float x = m % 2 == 0 ? c.u + c.v : c.u, y = m % 2 == 0 ? c.v : c.u + c.v;
            const bool on = leaf(m / 2, x, y);
            alpha::setState2(d2, idx, on ? 1u : 0u);
            opaque += on;
            const uint32_t coarse = alpha::microTriangleIndex(c.u, c.v, o.level4);
            if (coarse != idx >> (2 * (o.level - o.level4))) ++s.hierarchyMismatches;
            coarseOpaque[coarse] += on, coarseTotal[coarse] += 1;
        }
        uint8_t* d4 = &s.states4[size_t(m) * b4];
        for (uint32_t i = 0; i < nCoarse; ++i) {
            const uint32_t on = coarseOpaque[i], all = coarseTotal[i];
            // 0 transparent, 1 opaque, 2 unknown-transparent, 3 unknown-opaque (both "non-opaque" to traversal)
            const uint32_t st = on == 0 ? 0u : on == all ? 1u : 2 * on >= all ? 3u : 2u;
            unknown += st >= 2;
            alpha::setState4(d4, i, st);
        }
    }
    s.opaqueFraction = double(opaque) / (double(nFine) * 2 * o.patterns);
    s.unknownFraction = double(unknown) / (double(nCoarse) * 2 * o.patterns);
    return s;
}

// ----------------------------------------------------------------------------------------------------------------
// Rays
// ----------------------------------------------------------------------------------------------------------------

enum Kind { kCamera, kRandom, kShadow, kKinds };
const char* kKindName[kKinds] = {"camera", "random", "shadow"};
const bool kAnyHit[kKinds] = {false, false, true};

VkasRay makeRay(const double o[3], const double d[3], float tMax) {
    return {{float(o[0]), float(o[1]), float(o[2])}, 0.0f, {float(d[0]), float(d[1]), float(d[2])}, tMax};
}

void normalize(double d[3]) {
    const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int k = 0; k < 3; ++k) d[k] /= l;
}

std::vector<VkasRay> makeRays(Kind kind, size_t count, uint64_t seed) {
    std::vector<VkasRay> rays;
    rays.reserve(count);
    if (kind == kCamera) {
        // A pinhole camera outside the volume looking at its centre; the image covers the volume.
        double back[3] = {0.3, 0.4, 1.0};
        normalize(back);
        const double dist = 2.2 * kHalf, halfFov = 25 * M_PI / 180, scale = std::tan(halfFov);
        const double eye[3] = {back[0] * dist, back[1] * dist, back[2] * dist};
        const double fwd[3] = {-back[0], -back[1], -back[2]};
        double right[3] = {-fwd[2], 0, fwd[0]};  // fwd x (0, 1, 0)
        normalize(right);
        const double up[3] = {right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
                              right[0] * fwd[1] - right[1] * fwd[0]};
        const size_t side = size_t(std::ceil(std::sqrt(double(count))));
        for (size_t i = 0; i < count; ++i) {
            const double sx = (2 * ((i % side) + 0.5) / side - 1) * scale, sy = (1 - 2 * ((i / side) + 0.5) / side) * scale;
            double d[3];
            for (int k = 0; k < 3; ++k) d[k] = fwd[k] + sx * right[k] + sy * up[k];
            normalize(d);
            rays.push_back(makeRay(eye, d, INFINITY));
        }
        return rays;
    }
    std::mt19937_64 rng(seed * 1000003u + uint64_t(kind));
    std::uniform_real_distribution<double> uni(-kHalf, kHalf);
    std::normal_distribution<double> gauss;
    for (size_t i = 0; i < count; ++i) {
        const double o[3] = {uni(rng), uni(rng), uni(rng)};
        double d[3];
        float tMax = INFINITY;
        if (kind == kRandom) {
            d[0] = gauss(rng), d[1] = gauss(rng), d[2] = gauss(rng);
        } else {  // a segment between two random points of the volume
            const double p[3] = {uni(rng), uni(rng), uni(rng)};
            for (int k = 0; k < 3; ++k) d[k] = p[k] - o[k];
            tMax = float(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
        }
        normalize(d);
        rays.push_back(makeRay(o, d, tMax));
    }
    return rays;
}

struct Hit {
    int32_t prim = -1;
    float t = 0, u = 0, v = 0;
    bool hit() const { return prim >= 0; }
};

// ----------------------------------------------------------------------------------------------------------------
// vkas
// ----------------------------------------------------------------------------------------------------------------

void check(VkResult r, const char* what) {
    if (r != VK_SUCCESS) throw std::runtime_error(std::string("vkas: ") + what + " failed (" + std::to_string(int(r)) + ")");
}

// The commands (vkCreateBuffer etc.; the micromap ones NULL when missing) are vkas_kit::Commands' (kit/).
class Vkas : public vkas_kit::Commands {
public:
    struct Memory {
        VkBuffer buffer = VK_NULL_HANDLE;
        VkDeviceMemory memory = VK_NULL_HANDLE;
    };
    struct Structure {
        VkAccelerationStructureKHR as = VK_NULL_HANDLE;
        Memory mem;
        uint64_t compacted = 0;
        double ms = 0;  // build time, median
    };
    struct Micromap {
        VkMicromapEXT mm = VK_NULL_HANDLE;
        Memory mem;
        uint64_t size = 0;  // micromapSize of the build-sizes query; the compacted size where it can be queried
        double ms = 0;
    };

    Vkas(uint32_t threads, bool validate) {
        VkasDeviceCreateInfo ci{};
        ci.disableValidation = validate ? VK_FALSE : VK_TRUE;
        ci.workerThreadCount = threads;
        check(vkasCreateDevice(&ci, &dev_), "vkasCreateDevice");
        load(dev_);
    }
    ~Vkas() {
        for (Structure& s : structures_) {
            vkDestroyAccelerationStructureKHR(dev_, s.as, nullptr);
            release(s.mem);
        }
        for (Micromap& m : micromaps_) {
            vkDestroyMicromapEXT(dev_, m.mm, nullptr);
            release(m.mem);
        }
        vkasDestroyDevice(dev_);
    }
    Vkas(const Vkas&) = delete;
    Vkas& operator=(const Vkas&) = delete;

    VkDevice device() const { return dev_; }
    bool hasMicromaps() const {
        return vkCreateMicromapEXT && vkDestroyMicromapEXT && vkGetMicromapBuildSizesEXT && vkBuildMicromapsEXT;
    }

    // The micromap of the scene's patterns in one format (2 * patterns triangles).
    Micromap buildMicromap(const Scene& s, VkOpacityMicromapFormatEXT format, int reps) {
        const bool two = format == VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT;
        const uint32_t level = two ? s.level : s.level4, bytes = two ? alpha::bytes2(level) : alpha::bytes4(level);
        const std::vector<uint8_t>& data = two ? s.states2 : s.states4;
        const uint32_t count = 2 * s.patterns;
        std::vector<VkMicromapTriangleEXT> tris(count);
        for (uint32_t i = 0; i < count; ++i) tris[i] = {i * bytes, uint16_t(level), uint16_t(format)};
        const VkMicromapUsageEXT usage{count, level, uint32_t(format)};
        VkMicromapBuildInfoEXT info{VK_STRUCTURE_TYPE_MICROMAP_BUILD_INFO_EXT};
        info.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        info.flags = VK_BUILD_MICROMAP_ALLOW_COMPACTION_BIT_EXT;
        info.mode = VK_BUILD_MICROMAP_MODE_BUILD_EXT;
        info.usageCountsCount = 1;
        info.pUsageCounts = &usage;
        info.data.hostAddress = data.data();
        info.triangleArray.hostAddress = tris.data();
        info.triangleArrayStride = sizeof(VkMicromapTriangleEXT);
        VkMicromapBuildSizesInfoEXT sizes{VK_STRUCTURE_TYPE_MICROMAP_BUILD_SIZES_INFO_EXT};
        vkGetMicromapBuildSizesEXT(dev_, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &sizes);
        Micromap m;
        m.mem = allocate(sizes.micromapSize, VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT);
        VkMicromapCreateInfoEXT ci{VK_STRUCTURE_TYPE_MICROMAP_CREATE_INFO_EXT};
        ci.buffer = m.mem.buffer;
        ci.size = sizes.micromapSize;
        ci.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        check(vkCreateMicromapEXT(dev_, &ci, nullptr, &m.mm), "vkCreateMicromapEXT");
        std::vector<uint8_t> scratch(std::max<VkDeviceSize>(sizes.buildScratchSize, 1));
        info.dstMicromap = m.mm;
        info.scratchData.hostAddress = scratch.data();
        std::vector<double> ms;
        for (int r = 0; r < reps; ++r) {
            const auto t0 = std::chrono::steady_clock::now();
            check(vkBuildMicromapsEXT(dev_, VK_NULL_HANDLE, 1, &info), "vkBuildMicromapsEXT");
            ms.push_back(msSince(t0));
        }
        m.ms = median(ms);
        m.size = sizes.micromapSize;
        uint64_t compacted = 0;
        if (vkWriteMicromapsPropertiesEXT &&
            vkWriteMicromapsPropertiesEXT(dev_, 1, &m.mm, VK_QUERY_TYPE_MICROMAP_COMPACTED_SIZE_EXT, sizeof compacted,
                                          &compacted, sizeof compacted) == VK_SUCCESS &&
            compacted)
            m.size = compacted;
        micromaps_.push_back(m);
        return m;
    }

    // The quads' bottom level (non-opaque triangles; with `micromap`, its states decide the opacity) under one
    // identity instance. Returns the top level; `blas` gets the bottom level's build time and compacted size.
    VkAccelerationStructureKHR buildScene(const Scene& s, const Micromap* micromap, VkOpacityMicromapFormatEXT format,
                                          int reps, Structure* blasOut) {
        VkAccelerationStructureTrianglesOpacityMicromapEXT omm{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_TRIANGLES_OPACITY_MICROMAP_EXT};
        const VkMicromapUsageEXT usage{s.triangles(), format == VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT ? s.level : s.level4,
                                       uint32_t(format)};
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
        g.flags = 0;  // not OPAQUE: without micromap every candidate goes to the application
        auto& t = g.geometry.triangles;
        t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        t.vertexData.hostAddress = s.vertices.data();
        t.vertexStride = 12;
        t.maxVertex = s.vertexCount() - 1;
        t.indexType = VK_INDEX_TYPE_UINT32;
        t.indexData.hostAddress = s.indices.data();
        if (micromap) {
            omm.indexType = VK_INDEX_TYPE_UINT32;
            omm.indexBuffer.hostAddress = s.ommIndex.data();
            omm.indexStride = sizeof(uint32_t);
            omm.baseTriangle = 0;
            omm.usageCountsCount = 1;
            omm.pUsageCounts = &usage;
            omm.micromap = micromap->mm;
            t.pNext = &omm;
        }
        Structure blas = build(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, s.triangles(), reps);
        if (blasOut) *blasOut = blas;

        VkAccelerationStructureInstanceKHR inst{};
        const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
        std::memcpy(inst.transform.matrix, identity, sizeof identity);
        inst.mask = 0xFF;
        inst.accelerationStructureReference = uint64_t(blas.as);
        VkAccelerationStructureGeometryKHR ig{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        ig.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
        ig.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        ig.geometry.instances.data.hostAddress = &inst;
        return build(VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR, ig, 1, 1).as;
    }

private:
    Memory allocate(VkDeviceSize size, VkBufferUsageFlags usage) {
        Memory m;
        VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        bci.size = std::max<VkDeviceSize>(size, 256);
        bci.usage = usage;
        check(vkCreateBuffer(dev_, &bci, nullptr, &m.buffer), "vkCreateBuffer");
        VkMemoryRequirements req;
        vkGetBufferMemoryRequirements(dev_, m.buffer, &req);
        VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        mai.allocationSize = req.size;
        check(vkAllocateMemory(dev_, &mai, nullptr, &m.memory), "vkAllocateMemory");
        check(vkBindBufferMemory(dev_, m.buffer, m.memory, 0), "vkBindBufferMemory");
        return m;
    }
    void release(Memory& m) {
        if (m.buffer) vkDestroyBuffer(dev_, m.buffer, nullptr);
        if (m.memory) vkFreeMemory(dev_, m.memory, nullptr);
        m = {};
    }

    Structure build(VkAccelerationStructureTypeKHR type, const VkAccelerationStructureGeometryKHR& g, uint32_t count, int reps) {
        VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
        info.type = type;
        info.flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
        info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
        info.geometryCount = 1;
        info.pGeometries = &g;
        VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
        vkGetAccelerationStructureBuildSizesKHR(dev_, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info, &count, &sizes);
        Structure s;
        s.mem = allocate(sizes.accelerationStructureSize, VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR);
        VkAccelerationStructureCreateInfoKHR ci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
        ci.buffer = s.mem.buffer;
        ci.size = sizes.accelerationStructureSize;
        ci.type = type;
        check(vkCreateAccelerationStructureKHR(dev_, &ci, nullptr, &s.as), "vkCreateAccelerationStructureKHR");
        std::vector<uint8_t> scratch(std::max<VkDeviceSize>(sizes.buildScratchSize, 1));
        info.dstAccelerationStructure = s.as;
        info.scratchData.hostAddress = scratch.data();
        const VkAccelerationStructureBuildRangeInfoKHR range{count, 0, 0, 0};
        const VkAccelerationStructureBuildRangeInfoKHR* pRange = &range;
        std::vector<double> ms;
        for (int r = 0; r < reps; ++r) {
            const auto t0 = std::chrono::steady_clock::now();
            check(vkBuildAccelerationStructuresKHR(dev_, VK_NULL_HANDLE, 1, &info, &pRange), "vkBuildAccelerationStructuresKHR");
            ms.push_back(msSince(t0));
        }
        s.ms = median(ms);
        check(vkWriteAccelerationStructuresPropertiesKHR(dev_, 1, &s.as, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                                                         sizeof s.compacted, &s.compacted, sizeof s.compacted),
              "vkWriteAccelerationStructuresPropertiesKHR");
        structures_.push_back(s);
        return s;
    }

    VkDevice dev_ = VK_NULL_HANDLE;
    std::vector<Structure> structures_;
    std::vector<Micromap> micromaps_;
};

// vkasTraceRays: closest hit, or any hit (ANY_HIT mode) for segments. Returns the time in ms.
double traceBatch(VkDevice dev, VkAccelerationStructureKHR tlas, bool anyHit, const std::vector<VkasRay>& rays,
                  std::vector<Hit>& hits) {
    std::vector<VkasHit> out(rays.size());
    const double c0 = threadCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    check(vkasTraceRays(dev, tlas, anyHit ? VKAS_TRACE_MODE_ANY_HIT : VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_RAY_FLAG_NONE,
                        0xFF, uint32_t(rays.size()), rays.data(), out.data()),
          "vkasTraceRays");
    const double ms = msSince(t0);
    gCpuMs = threadCpuMs() - c0;
    hits.assign(rays.size(), Hit{});
    for (size_t i = 0; i < rays.size(); ++i)
        if (out[i].type != VKAS_COMMITTED_INTERSECTION_NONE)
            hits[i] = {out[i].primitiveIndex, out[i].t, out[i].barycentrics[0], out[i].barycentrics[1]};
    return ms;
}

// The ray-query loop: every triangle candidate that Proceed returns (non-opaque) is alpha-tested at its barycentrics
// and confirmed if opaque. `candidates` counts them. The hits are written inside the timed loop, as vkasTraceRays
// writes its VkasHit.
// alphaTest false: every candidate confirmed (the alpha ignored), for the context rows.
double traceRayQuery(const Scene& s, VkAccelerationStructureKHR tlas, bool anyHit, const std::vector<VkasRay>& rays,
                     std::vector<Hit>& hits, unsigned threads, uint64_t& candidates, bool alphaTest = true) {
    hits.assign(rays.size(), Hit{});
    std::atomic<uint64_t> total{0};
    const uint32_t flags = anyHit ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : VKAS_RAY_FLAG_NONE;
    const double c0 = threadCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    parallelFor(threads, rays.size(), kChunk, [&](size_t begin, size_t end) {
        auto q = std::make_unique<VkasRayQuery>();
        uint64_t seen = 0;
        for (size_t i = begin; i < end; ++i) {
            const VkasRay& r = rays[i];
            vkasRayQueryInitialize(q.get(), tlas, flags, 0xFF, r.origin, r.tMin, r.direction, r.tMax);
            while (vkasRayQueryProceed(q.get())) {
                if (vkasRayQueryGetIntersectionType(q.get(), VK_FALSE) != VKAS_CANDIDATE_INTERSECTION_TRIANGLE) continue;
                ++seen;
                float b[2];
                vkasRayQueryGetIntersectionBarycentrics(q.get(), VK_FALSE, b);
                const uint32_t prim = uint32_t(vkasRayQueryGetIntersectionPrimitiveIndex(q.get(), VK_FALSE));
                if (!alphaTest || s.opaque(prim, b[0], b[1])) vkasRayQueryConfirmIntersection(q.get());
            }
            if (vkasRayQueryGetIntersectionType(q.get(), VK_TRUE) == VKAS_COMMITTED_INTERSECTION_TRIANGLE) {
                float b[2];
                vkasRayQueryGetIntersectionBarycentrics(q.get(), VK_TRUE, b);
                hits[i] = {vkasRayQueryGetIntersectionPrimitiveIndex(q.get(), VK_TRUE),
                           vkasRayQueryGetIntersectionT(q.get(), VK_TRUE), b[0], b[1]};
            }
        }
        total.fetch_add(seen);
    });
    const double ms = msSince(t0);
    gCpuMs = threadCpuMs() - c0;
    candidates = total.load();
    return ms;
}

// ----------------------------------------------------------------------------------------------------------------
// Embree
// ----------------------------------------------------------------------------------------------------------------

struct FilterContext {
    const Scene* scene;
};

// The intersection and occlusion filter: rejects hits on transparent micro-triangles. Embree's (u, v) are the
// barycentric weights of vertices 1 and 2, as Vulkan's.
void alphaFilter(const RTCFilterFunctionNArguments* args) {
    const Scene& s = *static_cast<const FilterContext*>(args->geometryUserPtr)->scene;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const uint32_t prim = RTCHitN_primID(args->hit, args->N, i);
        if (!s.opaque(prim, RTCHitN_u(args->hit, args->N, i), RTCHitN_v(args->hit, args->N, i))) args->valid[i] = 0;
    }
}

bool embreeMonitor(void* user, ssize_t bytes, bool) {
    static_cast<std::atomic<int64_t>*>(user)->fetch_add(bytes);
    return true;
}

class Embree {
public:
    Embree(const Scene& s, bool robust, int reps) : ctx_{&s} {
        device_ = rtcNewDevice("threads=1");
        if (!device_) throw std::runtime_error("rtcNewDevice failed");
        if (!rtcGetDeviceProperty(device_, RTC_DEVICE_PROPERTY_FILTER_FUNCTION_SUPPORTED))
            throw std::runtime_error("this Embree has no filter functions");
        rtcSetDeviceMemoryMonitorFunction(device_, embreeMonitor, &memory_);
        std::vector<double> ms;
        for (int r = 0; r < reps; ++r) {
            if (scene_) rtcReleaseScene(scene_);
            scene_ = rtcNewScene(device_);
            rtcSetSceneFlags(scene_, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
            rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
            RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
            rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s.vertices.data(), 0, 12, s.vertexCount());
            rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s.indices.data(), 0, 12, s.triangles());
            rtcSetGeometryIntersectFilterFunction(g, alphaFilter);
            rtcSetGeometryOccludedFilterFunction(g, alphaFilter);
            rtcSetGeometryUserData(g, &ctx_);
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(scene_, g, 0);
            rtcReleaseGeometry(g);
            const int64_t before = memory_.load();
            const auto t0 = std::chrono::steady_clock::now();
            tbb::task_arena arena{1};  // threads=1 alone does not confine Embree's commit (bench/vs_embree does the same)
            arena.execute([&] { rtcCommitScene(scene_); });
            ms.push_back(msSince(t0));
            bytes_ = memory_.load() - before;
        }
        ms_ = median(ms);
    }
    ~Embree() {
        if (scene_) rtcReleaseScene(scene_);
        rtcReleaseDevice(device_);
    }
    double buildMs() const { return ms_; }
    int64_t bytes() const { return bytes_; }

    // rtcIntersect1 / rtcOccluded1 per ray (packet 0), or rtcIntersect8 / rtcIntersect16 packets (packet 8 or 16,
    // closest hit only).
    double trace(bool anyHit, bool coherent, int packet, const std::vector<VkasRay>& rays, std::vector<Hit>& hits,
                 unsigned threads) const {
        hits.assign(rays.size(), Hit{});
        const double c0 = threadCpuMs();
        const auto t0 = std::chrono::steady_clock::now();
        parallelFor(threads, rays.size(), kChunk, [&](size_t begin, size_t end) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            ctx.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
            if (packet == 0) {
                for (size_t i = begin; i < end; ++i) {
                    const VkasRay& v = rays[i];
                    RTCRayHit rh;
                    rh.ray.org_x = v.origin[0], rh.ray.org_y = v.origin[1], rh.ray.org_z = v.origin[2], rh.ray.tnear = v.tMin;
                    rh.ray.dir_x = v.direction[0], rh.ray.dir_y = v.direction[1], rh.ray.dir_z = v.direction[2];
                    rh.ray.time = 0, rh.ray.tfar = v.tMax, rh.ray.mask = 0xFFFFFFFFu, rh.ray.id = 0, rh.ray.flags = 0;
                    if (anyHit) {
                        rtcOccluded1(scene_, &ctx, &rh.ray);
                        if (rh.ray.tfar < 0) hits[i].prim = 0;  // occluded: tfar = -inf; no primitive reported
                    } else {
                        rh.hit.geomID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                        rtcIntersect1(scene_, &ctx, &rh);
                        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
                            hits[i] = {int32_t(rh.hit.primID), rh.ray.tfar, rh.hit.u, rh.hit.v};
                    }
                }
                return;
            }
            auto packets = [&](auto& p, auto call, size_t w) {
                alignas(64) int valid[16];
                for (size_t b = begin; b < end; b += w) {
                    for (size_t j = 0; j < w; ++j) {
                        const VkasRay& v = rays[std::min(b + j, end - 1)];
                        valid[j] = b + j < end ? -1 : 0;
                        p.ray.org_x[j] = v.origin[0], p.ray.org_y[j] = v.origin[1], p.ray.org_z[j] = v.origin[2];
                        p.ray.dir_x[j] = v.direction[0], p.ray.dir_y[j] = v.direction[1], p.ray.dir_z[j] = v.direction[2];
                        p.ray.tnear[j] = v.tMin, p.ray.tfar[j] = v.tMax, p.ray.time[j] = 0;
                        p.ray.mask[j] = 0xFFFFFFFFu, p.ray.id[j] = 0, p.ray.flags[j] = 0;
                        p.hit.geomID[j] = p.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
                    }
                    call(valid, scene_, &ctx, &p);
                    for (size_t j = 0; j < w && b + j < end; ++j)
                        if (p.hit.geomID[j] != RTC_INVALID_GEOMETRY_ID)
                            hits[b + j] = {int32_t(p.hit.primID[j]), p.ray.tfar[j], p.hit.u[j], p.hit.v[j]};
                }
            };
            if (packet == 8) {
                alignas(64) RTCRayHit8 p;
                packets(p, rtcIntersect8, 8);
            } else {
                alignas(64) RTCRayHit16 p;
                packets(p, rtcIntersect16, 16);
            }
        });
        const double ms = msSince(t0);
        gCpuMs = threadCpuMs() - c0;
        return ms;
    }

private:
    FilterContext ctx_;
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
    std::atomic<int64_t> memory_{0};
    int64_t bytes_ = 0;
    double ms_ = 0;
};

// ----------------------------------------------------------------------------------------------------------------
// Hit comparison
// ----------------------------------------------------------------------------------------------------------------

// Within 2^-16 (barycentric units) of an edge of the triangle or of a micro-triangle of the exact alpha: where float
// rounding of the barycentrics may select another micro-triangle (a micro-triangle's legs are 2^-level long).
bool nearMicroEdge(const Scene& s, const Hit& h) {
    const float d = 1.0f / 65536;
    if (std::min({h.u, h.v, 1 - h.u - h.v}) < d) return true;
    const uint32_t i = alpha::microTriangleIndex(h.u, h.v, s.level);
    for (const float du : {-d, 0.0f, d})
        for (const float dv : {-d, 0.0f, d})
            if (alpha::microTriangleIndex(h.u + du, h.v + dv, s.level) != i) return true;
    return false;
}

struct Agreement {
    size_t identical = 0;   // the same primitive and t bit for bit (or both miss)
    size_t sameNear = 0;    // the same primitive, t within the tolerance
    size_t tie = 0;         // another primitive at the same t (the quads' shared diagonal, crossing quads)
    size_t differ = 0;      // anything else (any hit: hit against miss)
    size_t differEdge = 0;  // ... where the nearer hit lies within 2^-16 of a (micro-)triangle edge
    size_t differing() const { return differ; }
};

size_t gShow = 0;  // --show-differences

void showDifference(const Scene& s, const char* what, size_t i, const Hit& a, const Hit& b, bool anyHit) {
    auto one = [&](const Hit& h) {
        char buf[160];
        if (!h.hit()) return std::string("miss");
        if (anyHit) return std::string("hit");
        std::snprintf(buf, sizeof buf, "prim %d t %.9g uv (%.9g, %.9g) micro-triangle %u (%s)%s", h.prim, double(h.t),
                      double(h.u), double(h.v), alpha::microTriangleIndex(h.u, h.v, s.level),
                      s.opaque(uint32_t(h.prim), h.u, h.v) ? "opaque" : "transparent", nearMicroEdge(s, h) ? ", at an edge" : "");
        return std::string(buf);
    };
    std::printf("  %s, ray %zu: reference %s; other %s\n", what, i, one(a).c_str(), one(b).c_str());
}

Agreement compare(const Scene& s, const std::vector<Hit>& ref, const std::vector<Hit>& other, bool anyHit,
                  const char* what = "") {
    Agreement g;
    size_t shown = 0;
    auto show = [&](size_t i) {
        if (shown++ < gShow) showDifference(s, what, i, ref[i], other[i], anyHit);
    };
    for (size_t i = 0; i < ref.size(); ++i) {
        const Hit &a = ref[i], &b = other[i];
        if (a.hit() != b.hit()) {
            ++g.differ;
            if (!anyHit && nearMicroEdge(s, a.hit() ? a : b)) ++g.differEdge;
            show(i);
            continue;
        }
        if (!a.hit() || anyHit) {
            ++g.identical;
            continue;
        }
        const float tol = 1e-4f * std::max(a.t, b.t) + 1e-5f;
        if (a.prim == b.prim) {
            if (std::memcmp(&a.t, &b.t, sizeof a.t) == 0) ++g.identical;
            else if (std::fabs(a.t - b.t) <= tol) ++g.sameNear;
            else ++g.differ, show(i);
            continue;
        }
        if (std::fabs(a.t - b.t) <= tol) {
            ++g.tie;
            continue;
        }
        ++g.differ;
        if (nearMicroEdge(s, a.t < b.t ? a : b)) ++g.differEdge;
        show(i);
    }
    return g;
}

// ----------------------------------------------------------------------------------------------------------------
// Report
// ----------------------------------------------------------------------------------------------------------------

std::string jsonString(const std::string& s) {
    std::string r = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') r += '\\';
        if (c == '\n') {
            r += "\\n";
            continue;
        }
        r += c;
    }
    return r + "\"";
}

std::string cpuModel() {
    std::ifstream f("/proc/cpuinfo");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("model name", 0) == 0) {
            const size_t c = line.find(':');
            return c == std::string::npos ? line : line.substr(c + 2);
        }
    return "unknown";
}

struct Row {
    Kind kind;
    std::string variant, call;
    double mrays1 = 0, mraysN = 0;  // 0: not run
    double mraysCpu1 = 0;           // 1 thread, by the thread's CPU time
    double candidatesPerRay = -1;   // rays-query variants: non-opaque candidates returned to the application per ray
    Agreement agree1, agreeN;
    bool compared = false;
};

}  // namespace

int main(int argc, char** argv) {
    const Options o = parse(argc, argv);
    gShow = o.showDifferences;
    std::string command = "vkas_bench_alpha";
    for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
    try {
        const auto tScene = std::chrono::steady_clock::now();
        const Scene scene = makeScene(o);
        std::printf("vkas_bench_alpha: %u quads (%u triangles) in [-50, 50]^3, half-extents %.2f..%.2f, %u leaf patterns, "
                    "seed %llu (%.0f ms to generate)\n",
                    scene.quads, scene.triangles(), 0.5 * o.size, double(o.size), scene.patterns,
                    (unsigned long long)o.seed, msSince(tScene));
        std::printf("alpha: level %u (%u micro-triangles per triangle), %.1f%% opaque; 4-state micromap level %u, %.1f%% of its "
                    "micro-triangles unknown\n",
                    scene.level, 1u << (2 * scene.level), 100 * scene.opaqueFraction, scene.level4, 100 * scene.unknownFraction);
        if (scene.hierarchyMismatches)
            std::printf("WARNING: %zu fine micro-triangles do not nest in the coarse one their index names\n",
                        scene.hierarchyMismatches);
        std::printf("machine: %s, %u hardware threads; %zu rays per kind, median of %d, all threads = %u\n", cpuModel().c_str(),
                    std::thread::hardware_concurrency(), o.rays, o.reps, o.threads);

        Vkas vk1(1, o.validate), vkN(o.threads, o.validate);
        bool omm = vk1.hasMicromaps();
        if (!omm)
            std::printf("vkas: vkasGetDeviceProcAddr(\"vkCreateMicromapEXT\") is NULL: this vkas has no micromap commands, "
                        "the micromap variants are skipped\n");

        // --- builds (1 thread) ---
        struct BuildRow {
            std::string what;
            double ms;
            double bytes;
        };
        std::vector<BuildRow> builds;
        Vkas::Structure blas;
        const VkAccelerationStructureKHR tlasConfirm1 =
            vk1.buildScene(scene, nullptr, VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT, o.reps, &blas);
        builds.push_back({"vkas BLAS, non-opaque (confirmation)", blas.ms, double(blas.compacted)});
        const VkAccelerationStructureKHR tlasConfirmN =
            vkN.buildScene(scene, nullptr, VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT, 1, nullptr);
        VkAccelerationStructureKHR tlasOmm2[2] = {}, tlasOmm4[2] = {};
        if (omm) try {
            for (int f = 0; f < 2; ++f) {
                const VkOpacityMicromapFormatEXT format = f == 0 ? VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT : VK_OPACITY_MICROMAP_FORMAT_4_STATE_EXT;
                const Vkas::Micromap m1 = vk1.buildMicromap(scene, format, o.reps);
                const Vkas::Micromap mN = vkN.buildMicromap(scene, format, 1);
                const std::string name = f == 0 ? "2-state" : "4-state";
                builds.push_back({"vkas micromap " + name + " (" + std::to_string(2 * scene.patterns) + " triangles, level " +
                                      std::to_string(f == 0 ? scene.level : scene.level4) + ")",
                                  m1.ms, double(m1.size)});
                Vkas::Structure b;
                (f == 0 ? tlasOmm2 : tlasOmm4)[0] = vk1.buildScene(scene, &m1, format, o.reps, &b);
                (f == 0 ? tlasOmm2 : tlasOmm4)[1] = vkN.buildScene(scene, &mN, format, 1, nullptr);
                builds.push_back({"vkas BLAS + " + name + " micromap", b.ms, double(b.compacted)});
            }
        } catch (const std::exception& e) {  // e.g. the commands exist but a build with a micromap is refused
            std::printf("vkas: %s: the micromap variants are skipped\n", e.what());
            omm = false;
        }
        std::unique_ptr<Embree> embree;
        if (!o.noEmbree) {
            embree = std::make_unique<Embree>(scene, o.embreeRobust, o.reps);
            builds.push_back({std::string("Embree MEDIUM") + (o.embreeRobust ? ", ROBUST" : ", default flags"), embree->buildMs(),
                              double(embree->bytes())});
        }
        std::printf("\nbuilds, 1 thread (median of %d)       %10s %10s %12s %8s\n", o.reps, "ms", "Mtris/s", "bytes", "B/tri");
        for (const BuildRow& b : builds) {
            const bool mm = b.what.rfind("vkas micromap", 0) == 0;  // a micromap: no per-triangle rates
            char rate[32] = "-", perTri[32] = "-";
            if (!mm) {
                std::snprintf(rate, sizeof rate, "%.3f", scene.triangles() / b.ms / 1000);
                std::snprintf(perTri, sizeof perTri, "%.2f", b.bytes / scene.triangles());
            }
            std::printf("  %-44s %10.3f %10s %12.0f %8s\n", b.what.c_str(), b.ms, rate, b.bytes, perTri);
        }
        std::printf("  (the application's alpha data: %zu bytes of 2-state states, %zu bytes of micromap indices)\n",
                    scene.states2.size(), scene.ommIndex.size() * sizeof(uint32_t));

        // --- traversal ---
        // Per ray kind, the variants' runs are interleaved (round r runs every variant once on 1 thread and once on
        // all threads), so that a change of load on a shared machine falls on all of them alike; medians per variant.
        std::vector<Row> rows;
        bool bad = false;
        for (int k = 0; k < kKinds; ++k) {
            const Kind kind = Kind(k);
            const bool anyHit = kAnyHit[k];
            const std::vector<VkasRay> rays = makeRays(kind, o.rays, o.seed);
            const double n = double(rays.size());
            using Run = std::function<double(std::vector<Hit>&, unsigned threads, uint64_t& candidates)>;
            struct Runner {
                Row row;
                Run run;
                bool rayQuery = false, compared = true;
                std::vector<double> ms1, msN, cpu1;
                std::vector<Hit> h1, hN;
                uint64_t candidates = 0;
            };
            std::vector<Runner> runners;
            const unsigned T = o.threads;
            auto batch = [&](Vkas& one, VkAccelerationStructureKHR t1, Vkas& all, VkAccelerationStructureKHR tN) -> Run {
                const VkDevice d1 = one.device(), dN = all.device();
                return [&rays, d1, dN, t1, tN, anyHit](std::vector<Hit>& h, unsigned threads, uint64_t&) {
                    return threads == 1 ? traceBatch(d1, t1, anyHit, rays, h) : traceBatch(dN, tN, anyHit, rays, h);
                };
            };
            auto query = [&](VkAccelerationStructureKHR t1, VkAccelerationStructureKHR tN, bool alphaTest = true) -> Run {
                return [&, t1, tN, anyHit, alphaTest](std::vector<Hit>& h, unsigned threads, uint64_t& c) {
                    return traceRayQuery(scene, threads == 1 ? t1 : tN, anyHit, rays, h, threads, c, alphaTest);
                };
            };
            // 2. vkas + confirmation: the reference (the alpha at the very barycentrics)
            runners.push_back({Row{kind, "vkas confirmation", "vkasRayQuery* loop"}, query(tlasConfirm1, tlasConfirmN), true});
            // Context, not compared: the same non-opaque scene through vkasTraceRays, which confirms every candidate
            // (the alpha ignored: every quad opaque). What traversal alone costs on these quads.
            runners.push_back({Row{kind, "vkas no alpha (context)", anyHit ? "vkasTraceRays ANY_HIT" : "vkasTraceRays"},
                               batch(vk1, tlasConfirm1, vkN, tlasConfirmN), false, false});
            // ... and through the ray-query loop confirming every candidate: the ray-query path's own cost.
            runners.push_back({Row{kind, "vkas no alpha (context)", "vkasRayQuery* loop"},
                               query(tlasConfirm1, tlasConfirmN, false), true, false});
            if (omm) {
                // 1. vkas + 2-state micromap; 4. 4-state micromap + confirmation of the unknown micro-triangles
                runners.push_back({Row{kind, "vkas micromap 2-state", anyHit ? "vkasTraceRays ANY_HIT" : "vkasTraceRays"},
                                   batch(vk1, tlasOmm2[0], vkN, tlasOmm2[1])});
                runners.push_back({Row{kind, "vkas micromap 4-state + confirm", "vkasRayQuery* loop"},
                                   query(tlasOmm4[0], tlasOmm4[1]), true});
            }
            if (embree) {
                // 3. Embree + filter functions (and its 8-wide packets for the camera rays)
                runners.push_back({Row{kind, "Embree filter", anyHit ? "rtcOccluded1" : "rtcIntersect1"},
                                   [&, anyHit, kind](std::vector<Hit>& h, unsigned threads, uint64_t&) {
                                       return embree->trace(anyHit, kind == kCamera, 0, rays, h, threads);
                                   }});
                if (kind == kCamera)
                    for (const int w : {8, 16})
                        runners.push_back({Row{kind, "Embree filter", "rtcIntersect" + std::to_string(w)},
                                           [&, w](std::vector<Hit>& h, unsigned threads, uint64_t&) {
                                               return embree->trace(false, true, w, rays, h, threads);
                                           }});
            }
            for (int r = 0; r < o.reps; ++r)
                for (Runner& x : runners) {
                    uint64_t c = 0;
                    x.ms1.push_back(x.run(x.h1, 1, c));
                    x.cpu1.push_back(gCpuMs);
                    x.candidates = c;
                    if (T > 1) x.msN.push_back(x.run(x.hN, T, c));
                }
            const std::vector<Hit>& ref = runners[0].h1;
            for (Runner& x : runners) {
                Row row = x.row;
                row.mrays1 = n / median(x.ms1) / 1000;
                row.mraysCpu1 = n / median(x.cpu1) / 1000;
                if (T > 1) row.mraysN = n / median(x.msN) / 1000;
                if (x.rayQuery) row.candidatesPerRay = double(x.candidates) / n;
                row.compared = x.compared;
                if (x.compared) {
                    const std::string what = std::string(kKindName[k]) + " " + row.variant + " " + row.call;
                    if (&x != &runners[0]) row.agree1 = compare(scene, ref, x.h1, anyHit, (what + ", 1 thread").c_str());
                    if (T > 1) row.agreeN = compare(scene, ref, x.hN, anyHit, (what + ", all threads").c_str());
                }
                rows.push_back(row);
            }
            size_t hitsRef = 0;
            for (const Hit& h : ref) hitsRef += h.hit();
            std::printf("\n%s rays (%s): %.1f%% hit (reference: vkas confirmation, 1 thread)\n", kKindName[k],
                        anyHit ? "any hit" : "closest hit", 100.0 * double(hitsRef) / n);
        }

        // --- the table ---
        const std::string nt = std::to_string(o.threads) + "t";
        std::printf("\n%-7s %-32s %-22s %8s %8s %8s %7s %8s %8s %8s %8s %8s  %s\n", "rays", "variant", "call", "1t wall",
                    "1t cpu", (nt + " wall").c_str(), "scaling", "/conf 1t", ("/conf " + nt).c_str(), "/Emb 1t",
                    ("/Emb " + nt).c_str(), "cand/ray", "differing from the reference: 1t (at an edge), ties; all threads");
        for (const Row& r : rows) {
            const Row* conf = nullptr;
            const Row* emb = nullptr;
            for (const Row& x : rows)
                if (x.kind == r.kind) {
                    if (x.variant == "vkas confirmation") conf = &x;
                    if (x.variant == "Embree filter" && !emb) emb = &x;
                }
            auto ratio = [](double a, double b) {
                char buf[16];
                if (a <= 0 || b <= 0) return std::string("-");
                std::snprintf(buf, sizeof buf, "%.2fx", a / b);
                return std::string(buf);
            };
            auto agree = [&](const Agreement& g) {
                char buf[96];
                std::snprintf(buf, sizeof buf, "%zu (%zu), ties %zu", g.differ, g.differEdge, g.tie);
                return std::string(buf);
            };
            char cand[16] = "-";
            if (r.candidatesPerRay >= 0) std::snprintf(cand, sizeof cand, "%.2f", r.candidatesPerRay);
            std::printf("%-7s %-32s %-22s %8.3f %8.3f %8.3f %7s %8s %8s %8s %8s %8s  %s\n", kKindName[r.kind],
                        r.variant.c_str(), r.call.c_str(), r.mrays1, r.mraysCpu1, r.mraysN, ratio(r.mraysN, r.mrays1).c_str(),
                        ratio(r.mraysCpu1, conf ? conf->mraysCpu1 : 0).c_str(), ratio(r.mraysN, conf ? conf->mraysN : 0).c_str(),
                        ratio(r.mraysCpu1, emb ? emb->mraysCpu1 : 0).c_str(), ratio(r.mraysN, emb ? emb->mraysN : 0).c_str(),
                        cand,
                        r.variant == "vkas confirmation" ? ("reference; " + agree(r.agreeN)).c_str()
                        : !r.compared                    ? "not compared (other hits)"
                                                         : (agree(r.agree1) + "; " + agree(r.agreeN)).c_str());
            // The vkas variants must agree with the reference except at micro-edges; a micromap the build ignored
            // would differ on a large share of the rays.
            const size_t limit = size_t(std::max(2.0, 1e-4 * double(o.rays)));
            if (r.compared && (r.agree1.differ > limit || r.agreeN.differ > limit)) bad = true;
        }
        std::printf("Mrays/s. 1t wall / 1t cpu: one thread, by wall-clock time / by the thread's CPU time (other processes' "
                    "time left out); %s wall: all threads, wall clock. /conf, /Emb: rate over vkas confirmation's / Embree's "
                    "one-ray call (1t: by CPU time; %s: wall clock). cand/ray: triangle candidates returned to the "
                    "application per ray.\n",
                    nt.c_str(), nt.c_str());
        std::printf("Embree scene: MEDIUM, %s; vkas: default build flags, one identity instance, validation %s.\n",
                    o.embreeRobust ? "RTC_SCENE_FLAG_ROBUST" : "default flags", o.validate ? "on" : "off");
        if (bad)
            std::printf("WARNING: a variant differs from the reference on more than %.0e of the rays%s\n", 1e-4,
                        omm ? " (a micromap the bottom-level build ignores gives this)" : "");

        if (!o.json.empty()) {
            std::ostringstream j;
            char date[32] = "";
            const std::time_t now = std::time(nullptr);
            std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
            j << "{\n  \"program\": \"vkas_bench_alpha\",\n  \"date\": " << jsonString(date) << ",\n  \"command\": " << jsonString(command) << ",\n  \"cpu\": "
              << jsonString(cpuModel()) << ",\n  \"hardware_threads\": " << std::thread::hardware_concurrency()
              << ",\n  \"threads\": " << o.threads << ",\n  \"rays_per_kind\": " << o.rays << ",\n  \"reps\": " << o.reps
              << ",\n  \"scene\": {\"quads\": " << scene.quads << ", \"triangles\": " << scene.triangles()
              << ", \"patterns\": " << scene.patterns << ", \"level\": " << scene.level << ", \"level4\": " << scene.level4
              << ", \"opaque_fraction\": " << scene.opaqueFraction << ", \"unknown_fraction_4state\": " << scene.unknownFraction
              << ", \"seed\": " << o.seed << "},\n  \"micromap_commands\": " << (omm ? "true" : "false")
              << ",\n  \"embree_flags\": " << jsonString(o.embreeRobust ? "ROBUST" : "NONE") << ",\n  \"builds\": [";
            for (size_t i = 0; i < builds.size(); ++i)
                j << (i ? ",\n" : "\n") << "    {\"what\": " << jsonString(builds[i].what) << ", \"ms\": " << builds[i].ms
                  << ", \"bytes\": " << builds[i].bytes << "}";
            j << "\n  ],\n  \"traces\": [";
            for (size_t i = 0; i < rows.size(); ++i) {
                const Row& r = rows[i];
                j << (i ? ",\n" : "\n") << "    {\"rays\": " << jsonString(kKindName[r.kind]) << ", \"variant\": "
                  << jsonString(r.variant) << ", \"call\": " << jsonString(r.call) << ", \"mrays_1_thread\": " << r.mrays1
                  << ", \"mrays_1_thread_cpu\": " << r.mraysCpu1 << ", \"mrays_all_threads\": " << r.mraysN << ", \"candidates_per_ray\": " << r.candidatesPerRay
                  << ", \"differing_1_thread\": " << r.agree1.differ << ", \"differing_1_thread_at_edge\": " << r.agree1.differEdge
                  << ", \"ties_1_thread\": " << r.agree1.tie << ", \"differing_all_threads\": " << r.agreeN.differ
                  << ", \"differing_all_threads_at_edge\": " << r.agreeN.differEdge << "}";
            }
            j << "\n  ]\n}\n";
            std::ofstream f(o.json);
            f << j.str();
            if (!f) throw std::runtime_error("cannot write " + o.json);
        }
        return bad ? 1 : 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vkas_bench_alpha: %s\n", e.what());
        return 2;
    }
}
