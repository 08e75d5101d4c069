// The body of the batch traversal kernel (batch_kernel.hpp), included by batch_kernel.cpp once per instruction set
// (no include guard, on purpose):
// for SSE2 and, inside a target("avx2") region, for AVX2. It includes nothing: everything it calls is either defined
// in the enclosing namespace before the include (childEntries: the node test of that instruction set) or an inline
// function of a header included before (compiled for the baseline target, which an AVX2 function may inline).
// Every function here has internal linkage, so the two copies never meet at link time.

// Four triangles of a leaf screened at once: the lanes the exact test (intersectTriangle) may accept. The edge
// functions are computed with the same float operations as intersectTriangle; a lane is dropped only when all
// three are non-zero and of mixed signs, which intersectTriangle rejects without further ado. Lanes at or past
// `count` are copies of record 0 and are masked off.
static inline uint32_t screenFour(const format::TriangleRecord* rec, uint32_t count, const ShearedRay& r) {
    const float* f0 = &rec[0].v[0][0];
    const float* f1 = &rec[count > 1 ? 1 : 0].v[0][0];
    const float* f2 = &rec[count > 2 ? 2 : 0].v[0][0];
    const float* f3 = &rec[count > 3 ? 3 : 0].v[0][0];
    __m128 a0 = _mm_loadu_ps(f0), a1 = _mm_loadu_ps(f1), a2 = _mm_loadu_ps(f2), a3 = _mm_loadu_ps(f3);
    __m128 b0 = _mm_loadu_ps(f0 + 4), b1 = _mm_loadu_ps(f1 + 4), b2 = _mm_loadu_ps(f2 + 4),
           b3 = _mm_loadu_ps(f3 + 4);
    _MM_TRANSPOSE4_PS(a0, a1, a2, a3);  // v0.x, v0.y, v0.z, v1.x
    _MM_TRANSPOSE4_PS(b0, b1, b2, b3);  // v1.y, v1.z, v2.x, v2.y
    const __m128 v2z = _mm_setr_ps(f0[8], f1[8], f2[8], f3[8]);
    const __m128 p0[3] = {a0, a1, a2}, p1[3] = {a3, b0, b1}, p2[3] = {b2, b3, v2z};
    const __m128 ox = _mm_set1_ps(r.org[r.kx]), oy = _mm_set1_ps(r.org[r.ky]), oz = _mm_set1_ps(r.org[r.kz]);
    const __m128 sx = _mm_set1_ps(r.sx), sy = _mm_set1_ps(r.sy);
    const __m128 Az0 = _mm_sub_ps(p0[r.kz], oz), Bz0 = _mm_sub_ps(p1[r.kz], oz), Cz0 = _mm_sub_ps(p2[r.kz], oz);
    const __m128 Ax = _mm_sub_ps(_mm_sub_ps(p0[r.kx], ox), _mm_mul_ps(sx, Az0));
    const __m128 Ay = _mm_sub_ps(_mm_sub_ps(p0[r.ky], oy), _mm_mul_ps(sy, Az0));
    const __m128 Bx = _mm_sub_ps(_mm_sub_ps(p1[r.kx], ox), _mm_mul_ps(sx, Bz0));
    const __m128 By = _mm_sub_ps(_mm_sub_ps(p1[r.ky], oy), _mm_mul_ps(sy, Bz0));
    const __m128 Cx = _mm_sub_ps(_mm_sub_ps(p2[r.kx], ox), _mm_mul_ps(sx, Cz0));
    const __m128 Cy = _mm_sub_ps(_mm_sub_ps(p2[r.ky], oy), _mm_mul_ps(sy, Cz0));
    const __m128 U = _mm_sub_ps(_mm_mul_ps(Cx, By), _mm_mul_ps(Cy, Bx));
    const __m128 V = _mm_sub_ps(_mm_mul_ps(Ax, Cy), _mm_mul_ps(Ay, Cx));
    const __m128 W = _mm_sub_ps(_mm_mul_ps(Bx, Ay), _mm_mul_ps(By, Ax));
    const __m128 z = _mm_setzero_ps();
    const __m128 neg = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(U, z), _mm_cmplt_ps(V, z)), _mm_cmplt_ps(W, z));
    const __m128 pos = _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(U, z), _mm_cmpgt_ps(V, z)), _mm_cmpgt_ps(W, z));
    const __m128 zero = _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(U, z), _mm_cmpeq_ps(V, z)), _mm_cmpeq_ps(W, z));
    const uint32_t rejected = uint32_t(_mm_movemask_ps(_mm_andnot_ps(zero, _mm_and_ps(neg, pos))));
    return ~rejected & ((1u << (count < 4 ? count : 4)) - 1u);
}

struct Walk {
    ShearedRay worldRay, objectRay;
    float tMin, tMax;
    uint32_t flags, cullMask;
    const format::InstanceRecord* instance;
    QueryHit* committed;
    bool done;
};

// The triangle decision of the ray query (hit_rules.hpp) for a candidate that needs no application decision: a
// non-opaque one is confirmed on the spot, as queryRunToCompletion does.
static inline void testTriangleExact(Walk& w, const format::TriangleRecord& tri) {
    TriangleCandidate c;
    if (!triangleCandidate(w.objectRay, w.tMin, w.tMax, w.flags, w.instance->sbtOffsetAndFlags >> 24, tri, tri.v, c))
        return;
    setTriangleHit(*w.committed, kCommittedTriangle, c, tri, w.instance, w.objectRay);
    w.tMax = c.hit.t;
    if (w.flags & kRayTerminateOnFirstHit) w.done = true;
}

static inline void testTriangleLeaf(Walk& w, const format::TriangleRecord* records, format::ChildRef leaf) {
    const format::TriangleRecord* rec = records + format::leafFirst(leaf);
    for (uint32_t left = format::leafCount(leaf); left > 0;) {
        const uint32_t n = left < 4 ? left : 4;
        for (uint32_t lanes = screenFour(rec, n, w.objectRay); lanes != 0; lanes &= lanes - 1) {
            testTriangleExact(w, rec[__builtin_ctz(lanes)]);
            if (w.done) return;
        }
        rec += n;
        left -= n;
    }
}

// The children of `node` the ray enters, in the order of traversal_steps.hpp (the nearest last). Returns their number.
static inline uint32_t hitChildren(const format::Node& node, const ShearedRay& r, float tMin, float tMax,
                                   format::ChildRef ref[format::kNodeWidth], float dist[format::kNodeWidth]) {
    float entry[format::kNodeWidth];
    return orderHitChildren(node, childEntries(node, r, tMin, tMax, entry), entry, ref, dist);
}

// Walks one structure from `root` with the stack above `base`, calling leafFn(ref) for its leaves. A hit child is
// entered directly: the same as pushing it last and popping it at once (its entry distance passed the box test with
// the current tMax, so the pop's pruning test would pass too).
template <typename LeafFn>
static inline void walkTree(Walk& w, const format::Node* nodes, const ShearedRay& r, format::ChildRef root,
                            KernelScratch& s, uint32_t base, const LeafFn& leafFn) {
    uint32_t sp = base;
    pushChild(s.stackRef, s.stackDist, sp, root, w.tMin);
    while (sp > base) {
        --sp;
        format::ChildRef ref = s.stackRef[sp];
        if (s.stackDist[sp] > w.tMax * kFarSlack) continue;  // behind the committed hit
        while (format::isInternal(ref)) {
            format::ChildRef refs[format::kNodeWidth];
            float dist[format::kNodeWidth];
            const uint32_t hits = hitChildren(nodes[format::nodeIndex(ref)], r, w.tMin, w.tMax, refs, dist);
            if (hits == 0) {
                ref = format::kEmptyRef;
                break;
            }
            // Node and record loads are the cache misses of a traversal: ask for what the hit children need now.
            for (uint32_t k = 0; k < hits; ++k)
                if (format::isInternal(refs[k])) prefetchNode(nodes + format::nodeIndex(refs[k]));
            for (uint32_t k = 0; k + 1 < hits; ++k) pushChild(s.stackRef, s.stackDist, sp, refs[k], dist[k]);
            ref = refs[hits - 1];
        }
        if (format::isLeaf(ref)) {
            leafFn(ref, sp);
            if (w.done) return;
        }
    }
}

// The leaves of a bottom level: its triangles.
struct TriangleLeaves {
    Walk& w;
    const format::TriangleRecord* records;
    void operator()(format::ChildRef leaf, uint32_t) const { testTriangleLeaf(w, records, leaf); }
    void prefetch(format::ChildRef leaf) const {
        const char* p = reinterpret_cast<const char*>(records + format::leafFirst(leaf));
        const char* end = p + sizeof(format::TriangleRecord) * format::leafCount(leaf);
        for (; p < end; p += 64) _mm_prefetch(p, _MM_HINT_T0);
    }
};

// The leaves of the top level: instances, each entered as ray_query.cpp's enterInstance does.
struct InstanceLeaves {
    Walk& w;
    KernelScratch& s;
    BlasResolver resolver;
    const format::InstanceRecord* instances;
    bool& supported;

    const std::byte* resolve(uint64_t reference) const {
        if (reference == s.cachedReference && s.cachedBlas) return s.cachedBlas;
        const std::byte* blas = resolver ? resolver(reference) : nullptr;
        s.cachedReference = reference;
        s.cachedBlas = blas;
        return blas;
    }

    void prefetch(format::ChildRef leaf) const {
        _mm_prefetch(reinterpret_cast<const char*>(instances + format::leafFirst(leaf)), _MM_HINT_T0);
    }

    void operator()(format::ChildRef leaf, uint32_t sp) const {
        for (uint64_t i = format::leafFirst(leaf), end = i + format::leafCount(leaf); i < end; ++i) {
            const format::InstanceRecord& inst = instances[i];
            if (!instanceVisible(inst, w.cullMask)) continue;
            const std::byte* blas = resolve(inst.reference);
            const format::Header* h = traversableStructure(blas, format::StructureType::BottomLevel);
            if (!h) continue;
            // AABB candidates are dropped without an intersection step: such an instance adds nothing.
            if (h->primitiveType == VK_GEOMETRY_TYPE_AABBS_KHR || skippedByRayFlags(*h, w.flags)) continue;
            if (h->primitiveType != VK_GEOMETRY_TYPE_TRIANGLES_KHR || motion::isMotionBuild(h->buildFlags)) {
                supported = false;
                w.done = true;
                return;
            }
            float oo[3], od[3];
            transformRay(inst.worldToObject, w.worldRay.org, w.worldRay.dir, oo, od);
            prepareShearedRay(w.objectRay, oo, od);
            w.instance = &inst;
            walkTree(w, format::nodes(blas), w.objectRay, h->root, s, sp, TriangleLeaves{w, format::triangles(blas)});
            if (w.done) return;
        }
    }
};

static bool traceWith(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& s,
                      QueryHit& committed) {
    committed.type = kCommittedNone;  // the other fields are written with a hit
    committed.t = ray.tMax;
    const format::Header* top = traversableStructure(topLevel, format::StructureType::TopLevel);
    if (!top) return true;  // a null acceleration structure: every ray misses
    if (motion::isMotionBuild(top->buildFlags)) return false;
    Walk w;
    prepareShearedRay(w.worldRay, ray.origin, ray.direction);
    w.tMin = ray.tMin;
    w.tMax = ray.tMax;
    w.flags = ray.flags;
    w.cullMask = ray.cullMask;
    w.instance = nullptr;
    w.committed = &committed;
    w.done = false;
    bool supported = true;
    walkTree(w, format::nodes(topLevel), w.worldRay, top->root, s, 0,
             InstanceLeaves{w, s, resolver, format::instances(topLevel), supported});
    return supported;
}
