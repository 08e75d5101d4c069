// The body of the batch traversal kernel (batch_kernel.hpp), included by batch_kernel.cpp once per instruction set
// (no include guard, on purpose):
// for SSE2 and, inside target("avx2") and target("avx2,avx512f,avx512vl") regions, for AVX2 and AVX-512. It includes nothing: everything it calls is either defined
// in the enclosing namespace before the include (childEntries: the node test of that instruction set;
// transformInstanceRay: the world-to-object transform) or an inline
// function of a header included before (compiled for the baseline target, which an AVX2 function may inline).
// Every function here has internal linkage, so the copies never meet at link time.

struct Walk {
    ShearedRay worldRay, objectRay;  // worldRay: the box part only (prepareBoxRay)
    float tMin, tMax;
    uint32_t flags, cullMask;
    const format::InstanceRecord* instance;
    QueryHit* committed;
    bool done;
    bool tied;  // (packets) a triangle was met at exactly the committed t: the order of the two decided the hit
    bool needsQuery;  // (kForQuery) a candidate the application must see: the query's state machine takes the ray
};

// The triangle decision of the ray query (hit_rules.hpp) for each lane of a leaf that the four-lane test
// (triangle_leaf_intersector.hpp) leaves: a non-opaque candidate needs no application decision here and is confirmed on the
// spot, as queryRunToCompletion does. Lanes are taken in order, so hits and ties are the ray query's. With
// kFindTies (a ray of a packet, which meets the leaves in another order than it would alone), a triangle met at
// exactly the committed t is noted in w.tied: the strict interval drops it, so the order decided between the two.
// With kForQuery (a ray query's first proceed), a non-opaque candidate ends the walk with w.needsQuery: the
// application decides it, so the query's state machine traces the ray instead.
template <bool kFindTies, bool kForQuery = false>
static inline void testTriangleLeaf(Walk& w, const std::byte* blas, format::ChildRef leafRef) {
    const format::ConstTriangleLeaf leaf =
        format::triangleLeaf(format::records(blas), format::leafFirst(leafRef), format::leafCount(leafRef));
    const uint32_t instanceFlags = w.instance->sbtOffsetAndFlags >> 24;
    for (uint32_t lane0 = 0; lane0 < leaf.n; lane0 += 4) {
        FourLaneEdges e;
        edgesOfFour(leaf, lane0, leaf.n - lane0 < 4 ? leaf.n - lane0 : 4, w.objectRay, e);
        for (uint32_t lanes = e.covered | e.undecided; lanes != 0; lanes &= lanes - 1) {
            const uint32_t lane = uint32_t(__builtin_ctz(lanes));
            TriangleCandidate c;
            if (!leafLaneHit(leaf, lane0, lane, e, w.objectRay, c.hit)) continue;
            // (Another fragment of the committed triangle, format/fragment_section.hpp, is no tie: it is the same hit.)
            if (kFindTies && c.hit.t == w.tMax && w.committed->type != kCommittedNone &&
                !(w.committed->isTriangle && w.committed->instance == w.instance &&
                  w.committed->trianglePrimitiveIndex == leaf.primitiveIndex()[lane0 + lane] &&
                  w.committed->triangleGeometryIndex == leaf.geometryIndex(lane0 + lane)))
                w.tied = true;
            // acceptTriangleHit's first rule, asked here first: most candidates of a closest-hit walk lie past the
            // committed hit, and the call (with the triangle's identity gathered for it) is then not made.
            if (!insideTriangleInterval(c.hit.t, w.tMin, w.tMax)) continue;
            if (!acceptTriangleHit(w.objectRay, w.tMin, w.tMax, w.flags, instanceFlags, leaf.flags(lane0 + lane),
                                   leafTriangleId(blas, leaf, lane0 + lane), c))
                continue;
            if (kForQuery && !c.opaque) {
                w.needsQuery = w.done = true;
                return;
            }
            if (kForQuery) {  // the query's getters read the whole record
                float v[3][3];
                leaf.positions(lane0 + lane, v);
                setTriangleHit(*w.committed, kCommittedTriangle, c, leaf.geometryIndex(lane0 + lane),
                               leaf.primitiveIndex()[lane0 + lane], v, w.instance, w.objectRay);
            } else {  // a batch reports only part of it
                setReportedTriangleHit(*w.committed, c, leaf.geometryIndex(lane0 + lane),
                                       leaf.primitiveIndex()[lane0 + lane], w.instance);
            }
            w.tMax = c.hit.t;
            if (w.flags & kRayTerminateOnFirstHit) {
                w.done = true;
                return;
            }
        }
    }
}

// The children of `node` the ray enters, in the order of traversal_steps.hpp (the nearest last). Returns their number.
static inline uint32_t hitChildren(const format::Node& node, const NodeRay& r, float tMin, float tMax,
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
    // The ray and its interval in locals (registers): the stack's stores could alias them for the compiler, which
    // would reload them at every node. Only a leaf changes tMax.
    const NodeRay nodeRay = prepareNodeRay(r);
    const float tMin = w.tMin;
    float tMax = w.tMax;
    uint32_t sp = base;
    pushChild(s.stackRef, s.stackDist, sp, root, tMin);
    while (sp > base) {
        --sp;
        format::ChildRef ref = s.stackRef[sp];
        if (s.stackDist[sp] > tMax * kFarSlack) continue;  // behind the committed hit
        while (format::isInternal(ref)) {
            format::ChildRef refs[format::kNodeWidth];
            float dist[format::kNodeWidth];
            const uint32_t hits = hitChildren(nodes[format::nodeIndex(ref)], nodeRay, tMin, tMax, refs, dist);
            if (hits == 0) {
                ref = format::kEmptyRef;
                break;
            }
            // Node loads are the cache misses of a traversal: the children pushed for later are asked for now (the
            // one entered is read at once).
            for (uint32_t k = 0; k + 1 < hits; ++k) {
                if (format::isInternal(refs[k])) prefetchNode(nodes + format::nodeIndex(refs[k]));
                pushChild(s.stackRef, s.stackDist, sp, refs[k], dist[k]);
            }
            ref = refs[hits - 1];
        }
        if (format::isLeaf(ref)) {
            leafFn(ref, sp);
            if (w.done) return;
            tMax = w.tMax;
        }
    }
}

// The leaves of a bottom level: its triangles.
template <bool kFindTies, bool kForQuery = false>
struct TriangleLeaves {
    Walk& w;
    const std::byte* blas;
    void operator()(format::ChildRef leaf, uint32_t) const { testTriangleLeaf<kFindTies, kForQuery>(w, blas, leaf); }
};

// The bottom level an instance references, through the scratch's one-entry cache.
static inline const std::byte* resolveCached(KernelScratch& s, BlasResolver resolver, uint64_t reference) {
    if (reference == s.cachedReference && s.cachedBlas) return s.cachedBlas;
    const std::byte* blas = resolver ? resolver(reference) : nullptr;
    s.cachedReference = reference;
    s.cachedBlas = blas;
    return blas;
}

// The bottom level of an instance the kernel can walk: its header, or null when the ray skips it (no tree, AABBs,
// the Skip ray flags). Sets `supported` to false for what the kernel does not cover (motion, spheres, LSS; for a
// ray query, AABBs, whose candidates the application sees).
template <bool kForQuery = false>
static inline const format::Header* walkableBottomLevel(const std::byte* blas, uint32_t rayFlags, bool& supported) {
    const format::Header* h = traversableStructure(blas, format::StructureType::BottomLevel);
    if (!h || skippedByRayFlags(*h, rayFlags)) return nullptr;
    if (h->primitiveType == VK_GEOMETRY_TYPE_AABBS_KHR) {
        if (kForQuery) supported = false;  // (the batch drops AABB candidates without an intersection step)
        return nullptr;
    }
    if (h->primitiveType != VK_GEOMETRY_TYPE_TRIANGLES_KHR || motion::isMotionBuild(h->buildFlags)) {
        supported = false;
        return nullptr;
    }
    return h;
}

// The ray in the object space of `inst`, as ray_query.cpp's enterInstance does.
static inline void enterInstance(Walk& w, const format::InstanceRecord& inst) {
    float oo[3], od[3];
    transformInstanceRay(inst.worldToObject, w.worldRay.org, w.worldRay.dir, oo, od);
    prepareShearedRay(w.objectRay, oo, od);
    w.instance = &inst;
}

// The leaves of the top level: instances, each entered as ray_query.cpp's enterInstance does (kFindTies, kForQuery:
// testTriangleLeaf's).
template <bool kFindTies, bool kForQuery = false>
struct InstanceLeaves {
    Walk& w;
    KernelScratch& s;
    BlasResolver resolver;
    const format::InstanceRecord* instances;
    bool& supported;

    void operator()(format::ChildRef leaf, uint32_t sp) const {
        for (uint64_t i = format::leafFirst(leaf), end = i + format::leafCount(leaf); i < end; ++i) {
            const format::InstanceRecord& inst = instances[i];
            if (!instanceVisible(inst, w.cullMask)) continue;
            const std::byte* blas = resolveCached(s, resolver, inst.reference);
            const format::Header* h = walkableBottomLevel<kForQuery>(blas, w.flags, supported);
            if (!supported) {
                w.done = true;
                return;
            }
            if (!h) continue;
            enterInstance(w, inst);
            walkTree(w, format::nodes(blas), w.objectRay, h->root, s, sp,
                     TriangleLeaves<kFindTies, kForQuery>{w, blas});
            if (w.done) return;
        }
    }
};

// The world ray's origin and direction only: the box part (prepareBoxRay) is prepared where the top level has a node
// to test (its leaves are instances, whose rays are prepared in object space).
static inline void startWalk(Walk& w, const KernelRay& ray, QueryHit& committed) {
    for (int i = 0; i < 3; ++i) w.worldRay.org[i] = ray.origin[i], w.worldRay.dir[i] = ray.direction[i];
    w.tMin = ray.tMin;
    w.tMax = ray.tMax;
    w.flags = ray.flags;
    w.cullMask = ray.cullMask;
    w.instance = nullptr;
    w.committed = &committed;
    w.done = false;
    w.tied = false;
    w.needsQuery = false;
}

// kForQuery: for a ray query's first proceed (queryProceed): false also where a candidate needs the application.
template <bool kForQuery>
static bool traceRay(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& s,
                     QueryHit& committed) {
    committed.type = kCommittedNone;  // the other fields are written with a hit
    committed.t = ray.tMax;
    const format::Header* top = traversableStructure(topLevel, format::StructureType::TopLevel);
    if (!top) return true;  // a null acceleration structure: every ray misses
    if (motion::isMotionBuild(top->buildFlags)) return false;
    Walk w;
    startWalk(w, ray, committed);
    bool supported = true;
    const InstanceLeaves<false, kForQuery> leaves{w, s, resolver, format::instances(topLevel), supported};
    if (format::isLeaf(top->root)) {
        // A top level of one leaf (a few instances, the usual scene of one mesh): its instances are entered at once,
        // as walkTree would after pushing and popping the root (whose distance, tMin, it compares with tMax).
        if (!(w.tMin > w.tMax * kFarSlack)) leaves(top->root, 0);
    } else {
        prepareBoxRay(w.worldRay, ray.origin, ray.direction);
        walkTree(w, format::nodes(topLevel), w.worldRay, top->root, s, 0, leaves);
    }
    return supported && !w.needsQuery;
}

static bool traceWith(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& s,
                      QueryHit& committed) {
    return traceRay<false>(topLevel, resolver, ray, s, committed);
}

static bool traceForQueryWith(const std::byte* topLevel, BlasResolver resolver, const KernelRay& ray, KernelScratch& s,
                              QueryHit& committed) {
    return traceRay<true>(topLevel, resolver, ray, s, committed);
}
