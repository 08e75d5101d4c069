#include "embree_side.hpp"

#include <oneapi/tbb/task_arena.h>

#include <embree3/rtcore_builder.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace vb {
namespace {

bool monitor(void* user, ssize_t bytes, bool /*post*/) {
    auto* m = static_cast<EmbreeEngine::MemoryMonitor*>(user);
    const int64_t now = m->current.fetch_add(bytes) + bytes;
    int64_t peak = m->peak.load();
    while (now > peak && !m->peak.compare_exchange_weak(peak, now)) {
    }
    return true;
}

void setRay(RTCRay& r, const VkasRay& v) {
    r.org_x = v.origin[0], r.org_y = v.origin[1], r.org_z = v.origin[2], r.tnear = v.tMin;
    r.dir_x = v.direction[0], r.dir_y = v.direction[1], r.dir_z = v.direction[2], r.time = 0;
    r.tfar = v.tMax, r.mask = 0xFFFFFFFFu, r.id = 0, r.flags = 0;
}

Hit closest(const RTCRayHit& rh) {
    Hit h;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
    h.inst = rh.hit.instID[0] == RTC_INVALID_GEOMETRY_ID ? 0 : int32_t(rh.hit.instID[0]);
    h.prim = int32_t(rh.hit.primID), h.t = rh.ray.tfar, h.u = rh.hit.u, h.v = rh.hit.v;
    return h;
}

Hit occluded(float tfar) {
    Hit h;
    if (tfar < 0) h.inst = 0, h.prim = 0;  // rtcOccluded sets tfar to -inf when it finds a hit
    return h;
}

// --- rtcBuildBVH's user tree, for the SAH cost ---
struct UNode {
    bool leaf;
    unsigned count;  // children, or primitives of a leaf
    RTCBounds bounds[8];
    void* children[8];
};

void* createNode(RTCThreadLocalAllocator a, unsigned childCount, void*) {
    auto* n = static_cast<UNode*>(rtcThreadLocalAlloc(a, sizeof(UNode), 16));
    n->leaf = false, n->count = childCount;
    return n;
}
void setChildren(void* node, void** children, unsigned count, void*) {
    for (unsigned i = 0; i < count; ++i) static_cast<UNode*>(node)->children[i] = children[i];
}
void setBounds(void* node, const RTCBounds** bounds, unsigned count, void*) {
    for (unsigned i = 0; i < count; ++i) static_cast<UNode*>(node)->bounds[i] = *bounds[i];
}
void* createLeaf(RTCThreadLocalAllocator a, const RTCBuildPrimitive*, size_t count, void*) {
    auto* n = static_cast<UNode*>(rtcThreadLocalAlloc(a, sizeof(UNode), 16));
    n->leaf = true, n->count = unsigned(count);
    return n;
}

// Spatial split of a triangle fragment: the bounds of the triangle clipped to each side of the plane, limited to
// the fragment's current bounds.
void splitTriangle(const RTCBuildPrimitive* prim, unsigned dim, float pos, RTCBounds* left, RTCBounds* right, void* user) {
    const Mesh& m = *static_cast<const Mesh*>(user);
    const float* v[3];
    for (int k = 0; k < 3; ++k) v[k] = &m.vertices[3 * m.indices[3 * size_t(prim->primID) + k]];
    Box l, r;
    for (int k = 0; k < 3; ++k) {
        const float* a = v[k];
        const float* b = v[(k + 1) % 3];
        if (a[dim] <= pos) l.grow(a);
        if (a[dim] >= pos) r.grow(a);
        if ((a[dim] < pos && b[dim] > pos) || (a[dim] > pos && b[dim] < pos)) {
            const float t = (pos - a[dim]) / (b[dim] - a[dim]);
            float p[3];
            for (int c = 0; c < 3; ++c) p[c] = a[c] + t * (b[c] - a[c]);
            p[dim] = pos;
            l.grow(p), r.grow(p);
        }
    }
    const float lo[3] = {prim->lower_x, prim->lower_y, prim->lower_z}, hi[3] = {prim->upper_x, prim->upper_y, prim->upper_z};
    auto clip = [&](const Box& b, RTCBounds* out, bool isLeft) {
        float blo[3], bhi[3];
        for (int c = 0; c < 3; ++c) blo[c] = std::max(b.lo[c], lo[c]), bhi[c] = std::min(b.hi[c], hi[c]);
        if (isLeft) bhi[dim] = std::min(bhi[dim], pos);
        else blo[dim] = std::max(blo[dim], pos);
        out->lower_x = blo[0], out->lower_y = blo[1], out->lower_z = blo[2];
        out->upper_x = bhi[0], out->upper_y = bhi[1], out->upper_z = bhi[2];
    };
    clip(l, left, true);
    clip(r, right, false);
}

Box toBox(const RTCBounds& b) {
    Box r;
    r.lo[0] = b.lower_x, r.lo[1] = b.lower_y, r.lo[2] = b.lower_z;
    r.hi[0] = b.upper_x, r.hi[1] = b.upper_y, r.hi[2] = b.upper_z;
    return r;
}

SahCost sahOf(const UNode* root, const Box& rootBox) {
    SahCost c;
    c.rootArea = rootBox.area();
    if (!root) return c;
    if (root->leaf) {
        c.leaf(c.rootArea, root->count);
        return c;
    }
    std::vector<const UNode*> stack{root};
    while (!stack.empty()) {
        const UNode* n = stack.back();
        stack.pop_back();
        Box nodeBox;
        for (unsigned i = 0; i < n->count; ++i) {
            const Box b = toBox(n->bounds[i]);
            nodeBox.grow(b);
            const auto* child = static_cast<const UNode*>(n->children[i]);
            if (child->leaf) c.leaf(b.area(), child->count);
            else stack.push_back(child);
        }
        c.node(nodeBox.area());
    }
    return c;
}

SahCost buildUserBvh(RTCDevice device, std::vector<RTCBuildPrimitive>& prims, size_t count, RTCBuildQuality quality,
                     bool triangles, const Mesh* mesh) {
    Box rootBox;
    for (size_t i = 0; i < count; ++i) {
        const float lo[3] = {prims[i].lower_x, prims[i].lower_y, prims[i].lower_z};
        const float hi[3] = {prims[i].upper_x, prims[i].upper_y, prims[i].upper_z};
        rootBox.grow(lo), rootBox.grow(hi);
    }
    RTCBVH bvh = rtcNewBVH(device);
    RTCBuildArguments args = rtcDefaultBuildArguments();
    args.buildQuality = quality;
    args.maxBranchingFactor = 8;
    args.maxDepth = 64;
    args.sahBlockSize = triangles ? 4 : 1;
    args.minLeafSize = triangles ? 4 : 1;
    args.maxLeafSize = triangles ? RTC_BUILD_MAX_PRIMITIVES_PER_LEAF : 1;
    args.traversalCost = 1;
    args.intersectionCost = 1;
    args.bvh = bvh;
    args.primitives = prims.data();
    args.primitiveCount = count;
    args.primitiveArrayCapacity = prims.size();
    args.createNode = createNode;
    args.setNodeChildren = setChildren;
    args.setNodeBounds = setBounds;
    args.createLeaf = createLeaf;
    args.splitPrimitive = triangles && quality == RTC_BUILD_QUALITY_HIGH ? splitTriangle : nullptr;
    args.userPtr = const_cast<Mesh*>(mesh);
    const auto* root = static_cast<const UNode*>(rtcBuildBVH(&args));
    const SahCost c = sahOf(root, rootBox);
    rtcReleaseBVH(bvh);
    return c;
}

}  // namespace

const char* embreeCallName(EmbreeCall c, bool anyHit) {
    switch (c) {
        case EmbreeCall::One: return anyHit ? "rtcOccluded1" : "rtcIntersect1";
        case EmbreeCall::Packet8: return anyHit ? "rtcOccluded8" : "rtcIntersect8";
        case EmbreeCall::Packet16: return anyHit ? "rtcOccluded16" : "rtcIntersect16";
        case EmbreeCall::Stream: return anyHit ? "rtcOccluded1M" : "rtcIntersect1M";
    }
    return "?";
}

void EmbreeEngine::commit(RTCScene s) {
    if (threads_ == 0) return rtcCommitScene(s);
    tbb::task_arena arena{int(threads_)};
    arena.execute([&] { rtcCommitScene(s); });
}

EmbreeEngine::EmbreeEngine(unsigned threads) : threads_(threads) {
    const std::string config = threads ? "threads=" + std::to_string(threads) : std::string();
    device_ = rtcNewDevice(config.c_str());
    if (!device_) throw std::runtime_error("rtcNewDevice failed");
    rtcSetDeviceMemoryMonitorFunction(device_, monitor, &memory_);
}

EmbreeEngine::~EmbreeEngine() {
    for (RTCScene s : {traceScene_, traceChild_, defaultScene_, defaultChild_})
        if (s) rtcReleaseScene(s);
    rtcReleaseDevice(device_);
}

RTCScene EmbreeEngine::meshScene(const Mesh& mesh, RTCBuildQuality sceneQuality, RTCBuildQuality geometryQuality,
                                 RTCSceneFlags flags, const float* vertices) {
    RTCScene s = rtcNewScene(device_);
    rtcSetSceneFlags(s, flags);
    rtcSetSceneBuildQuality(s, sceneQuality);
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices, 0, 12, mesh.vertexCount());
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.indices.data(), 0, 12,
                               mesh.triangleCount());
    rtcSetGeometryBuildQuality(g, geometryQuality);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(s, g, 0);
    rtcReleaseGeometry(g);
    return s;
}

RTCScene EmbreeEngine::instanceScene(RTCScene child, const std::vector<Transform>& xs, RTCBuildQuality quality,
                                     RTCSceneFlags flags) {
    RTCScene s = rtcNewScene(device_);
    rtcSetSceneFlags(s, flags);
    rtcSetSceneBuildQuality(s, quality);
    for (size_t i = 0; i < xs.size(); ++i) {
        RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(g, child);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xs[i].data());
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(s, g, unsigned(i));
        rtcReleaseGeometry(g);
    }
    return s;
}

EmbreeEngine::Build EmbreeEngine::buildMesh(const Mesh& mesh, RTCBuildQuality quality, int reps) {
    Build b{1e300, 0};
    for (int r = 0; r < reps; ++r) {
        RTCScene s = meshScene(mesh, quality, quality, RTC_SCENE_FLAG_NONE, mesh.vertices.data());
        const int64_t before = memory_.load();
        memory_.peak.store(before);
        const auto t0 = std::chrono::steady_clock::now();
        commit(s);
        b.ms = std::min(b.ms, msSince(t0));
        b.bytes = memory_.load() - before;
        b.peakBytes = std::max(b.peakBytes, memory_.peak.load() - before);
        rtcReleaseScene(s);
    }
    return b;
}

EmbreeEngine::Build EmbreeEngine::refitMesh(const Mesh& mesh, const std::vector<float>& moved, int reps) {
    std::vector<float> vertices = mesh.vertices;  // Embree reads this shared buffer; rewritten between refits
    // Embree uses the geometry's build quality only in a scene of quality LOW (its two-level structure).
    RTCScene s = meshScene(mesh, RTC_BUILD_QUALITY_LOW, RTC_BUILD_QUALITY_REFIT,
                           RTCSceneFlags(RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_ROBUST), vertices.data());
    const int64_t before = memory_.load();
    commit(s);
    Build b{1e300, memory_.load() - before};
    RTCGeometry g = rtcGetGeometry(s, 0);
    const int runs = reps % 2 ? reps : reps + 1;
    for (int r = 0; r < runs; ++r) {
        const std::vector<float>& src = r % 2 == 0 ? moved : mesh.vertices;
        std::memcpy(vertices.data(), src.data(), src.size() * sizeof(float));
        const auto t0 = std::chrono::steady_clock::now();
        rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(g);
        commit(s);
        b.ms = std::min(b.ms, msSince(t0));
    }
    rtcReleaseScene(s);
    return b;
}

EmbreeEngine::Build EmbreeEngine::buildInstances(const Mesh& mesh, const std::vector<Transform>& xs,
                                                 RTCBuildQuality quality, int reps) {
    RTCScene child = meshScene(mesh, RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_MEDIUM, RTC_SCENE_FLAG_ROBUST,
                               mesh.vertices.data());
    commit(child);
    Build b{1e300, 0};
    for (int r = 0; r < reps; ++r) {
        RTCScene s = instanceScene(child, xs, quality, RTC_SCENE_FLAG_NONE);
        const int64_t before = memory_.load();
        const auto t0 = std::chrono::steady_clock::now();
        commit(s);
        b.ms = std::min(b.ms, msSince(t0));
        b.bytes = memory_.load() - before;
        rtcReleaseScene(s);
    }
    rtcReleaseScene(child);
    return b;
}

EmbreeEngine::Build EmbreeEngine::recommitInstances(const Mesh& mesh, const std::vector<Transform>& xs,
                                                    const std::vector<Transform>& moved, int reps) {
    RTCScene child = meshScene(mesh, RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_MEDIUM, RTC_SCENE_FLAG_ROBUST,
                               mesh.vertices.data());
    commit(child);
    RTCScene s = instanceScene(child, xs, RTC_BUILD_QUALITY_LOW,
                               RTCSceneFlags(RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_ROBUST));
    for (size_t i = 0; i < xs.size(); ++i) rtcSetGeometryBuildQuality(rtcGetGeometry(s, unsigned(i)), RTC_BUILD_QUALITY_REFIT);
    const int64_t before = memory_.load();
    commit(s);
    Build b{1e300, memory_.load() - before};
    const int runs = reps % 2 ? reps : reps + 1;
    for (int r = 0; r < runs; ++r) {
        const std::vector<Transform>& src = r % 2 == 0 ? moved : xs;
        for (size_t i = 0; i < xs.size(); ++i) {  // the new transforms (untimed, like writing vkas's instance records)
            RTCGeometry g = rtcGetGeometry(s, unsigned(i));
            rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, src[i].data());
            rtcCommitGeometry(g);
        }
        const auto t0 = std::chrono::steady_clock::now();
        commit(s);
        b.ms = std::min(b.ms, msSince(t0));
    }
    rtcReleaseScene(s);
    rtcReleaseScene(child);
    return b;
}

SahCost EmbreeEngine::userBvhSah(const Mesh& mesh, RTCBuildQuality quality) {
    const size_t n = mesh.triangleCount();
    std::vector<RTCBuildPrimitive> prims(quality == RTC_BUILD_QUALITY_HIGH ? 2 * n : n);
    for (size_t i = 0; i < n; ++i) {
        Box b;
        for (int k = 0; k < 3; ++k) b.grow(&mesh.vertices[3 * mesh.indices[3 * i + k]]);
        prims[i] = {b.lo[0], b.lo[1], b.lo[2], 0, b.hi[0], b.hi[1], b.hi[2], unsigned(i)};
    }
    return buildUserBvh(device_, prims, n, quality, true, &mesh);
}

SahCost EmbreeEngine::userBvhSah(const std::vector<Box>& boxes, RTCBuildQuality quality) {
    std::vector<RTCBuildPrimitive> prims(boxes.size());
    for (size_t i = 0; i < boxes.size(); ++i) {
        const Box& b = boxes[i];
        prims[i] = {b.lo[0], b.lo[1], b.lo[2], 0, b.hi[0], b.hi[1], b.hi[2], unsigned(i)};
    }
    return buildUserBvh(device_, prims, prims.size(), quality, false, nullptr);
}

void EmbreeEngine::makeTraceScene(const Scene& scene) {
    for (RTCScene* s : {&traceScene_, &traceChild_, &defaultScene_, &defaultChild_})
        if (*s) rtcReleaseScene(*s), *s = nullptr;
    for (const RTCSceneFlags flags : {RTC_SCENE_FLAG_ROBUST, RTC_SCENE_FLAG_NONE}) {
        RTCScene& top = flags == RTC_SCENE_FLAG_ROBUST ? traceScene_ : defaultScene_;
        RTCScene& child = flags == RTC_SCENE_FLAG_ROBUST ? traceChild_ : defaultChild_;
        RTCScene mesh = meshScene(scene.mesh, RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_MEDIUM, flags,
                                  scene.mesh.vertices.data());
        commit(mesh);
        if (!scene.manyInstances()) {
            top = mesh;
            continue;
        }
        child = mesh;
        top = instanceScene(mesh, scene.instances, RTC_BUILD_QUALITY_MEDIUM, flags);
        commit(top);
    }
}

double EmbreeEngine::trace(EmbreeCall call, bool anyHit, bool coherent, const std::vector<VkasRay>& rays,
                           std::vector<Hit>& hits, unsigned threads, int reps, TraceScene which) {
    hits.assign(rays.size(), Hit{});
    RTCScene scene = which == TraceScene::Robust ? traceScene_ : defaultScene_;
    const RTCIntersectContextFlags flags =
        coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    auto chunk = [&](size_t begin, size_t end) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags = flags;
        switch (call) {
            case EmbreeCall::One:
                for (size_t i = begin; i < end; ++i) {
                    RTCRayHit rh;
                    setRay(rh.ray, rays[i]);
                    if (anyHit) {
                        rtcOccluded1(scene, &ctx, &rh.ray);
                        hits[i] = occluded(rh.ray.tfar);
                    } else {
                        rh.hit.geomID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                        rtcIntersect1(scene, &ctx, &rh);
                        hits[i] = closest(rh);
                    }
                }
                break;
            case EmbreeCall::Packet8:
            case EmbreeCall::Packet16: {
                const size_t w = call == EmbreeCall::Packet8 ? 8 : 16;
                for (size_t b = begin; b < end; b += w) {
                    alignas(64) int valid[16];
                    alignas(64) RTCRayHit16 p;  // the 8-wide call uses the first 8 lanes of the same SoA layout
                    alignas(64) RTCRayHit8 p8;
                    for (size_t j = 0; j < w; ++j) {
                        const size_t i = std::min(b + j, end - 1);
                        valid[j] = b + j < end ? -1 : 0;
                        const VkasRay& v = rays[i];
                        auto fill = [&](auto& q) {
                            q.ray.org_x[j] = v.origin[0], q.ray.org_y[j] = v.origin[1], q.ray.org_z[j] = v.origin[2];
                            q.ray.dir_x[j] = v.direction[0], q.ray.dir_y[j] = v.direction[1], q.ray.dir_z[j] = v.direction[2];
                            q.ray.tnear[j] = v.tMin, q.ray.tfar[j] = v.tMax, q.ray.time[j] = 0;
                            q.ray.mask[j] = 0xFFFFFFFFu, q.ray.id[j] = 0, q.ray.flags[j] = 0;
                            q.hit.geomID[j] = q.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
                        };
                        if (w == 8) fill(p8);
                        else fill(p);
                    }
                    auto read = [&](auto& q) {
                        for (size_t j = 0; j < w && b + j < end; ++j) {
                            Hit& h = hits[b + j];
                            if (anyHit) {
                                h = occluded(q.ray.tfar[j]);
                            } else if (q.hit.geomID[j] != RTC_INVALID_GEOMETRY_ID) {
                                h.inst = q.hit.instID[0][j] == RTC_INVALID_GEOMETRY_ID ? 0 : int32_t(q.hit.instID[0][j]);
                                h.prim = int32_t(q.hit.primID[j]), h.t = q.ray.tfar[j], h.u = q.hit.u[j], h.v = q.hit.v[j];
                            }
                        }
                    };
                    if (w == 8) {
                        if (anyHit) rtcOccluded8(valid, scene, &ctx, &p8.ray);
                        else rtcIntersect8(valid, scene, &ctx, &p8);
                        read(p8);
                    } else {
                        if (anyHit) rtcOccluded16(valid, scene, &ctx, &p.ray);
                        else rtcIntersect16(valid, scene, &ctx, &p);
                        read(p);
                    }
                }
                break;
            }
            case EmbreeCall::Stream: {
                constexpr size_t M = 256;
                alignas(64) RTCRayHit stream[M];
                for (size_t b = begin; b < end; b += M) {
                    const size_t n = std::min(M, end - b);
                    for (size_t j = 0; j < n; ++j) {
                        setRay(stream[j].ray, rays[b + j]);
                        stream[j].hit.geomID = stream[j].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                    }
                    if (anyHit) rtcOccluded1M(scene, &ctx, &stream[0].ray, unsigned(n), sizeof(RTCRayHit));
                    else rtcIntersect1M(scene, &ctx, stream, unsigned(n), sizeof(RTCRayHit));
                    for (size_t j = 0; j < n; ++j) hits[b + j] = anyHit ? occluded(stream[j].ray.tfar) : closest(stream[j]);
                }
                break;
            }
        }
    };
    double best = 1e300;
    for (int r = 0; r < reps; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        parallelFor(threads, rays.size(), 1024, chunk);
        best = std::min(best, msSince(t0));
    }
    return best;
}

}  // namespace vb
