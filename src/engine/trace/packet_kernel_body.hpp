// The packet kernel (batch_kernel.hpp, tracePacket): up to kPacketWidth closest-hit rays of one octant traced
// together, included by batch_kernel.cpp once per instruction set after batch_kernel_body.hpp (whose Walk, walkTree
// and leaf tests it uses, with groupEntries and lanesEntering: the packet tests of that instruction set; no include
// guard, on purpose).
//
// Inner nodes are decided for the whole packet by the group test (packet_intersectors.hpp), one pass over the 8 children;
// each child that passes is then tested against each ray (the lane test, 8 rays a pass), and the rays that enter a
// leaf test its triangles alone, with the single-ray leaf test. Where the rays of a packet part ways (fewer than kPacketMinLanes enter a subtree, or their
// object-space rays at an instance leave the octant) they go on alone with walkTree.
//
// Each ray gets the single-ray kernel's hit: the group test never drops a child a ray enters, so every ray meets
// every triangle it would meet alone, with the same tests, and keeps the nearest. Only the order differs, and it
// matters only between triangles at the same t (the strict interval keeps the first met): a ray that meets a
// triangle at exactly its committed t is reported as tied, and the caller traces it again alone.

struct PacketWalk {
    uint32_t lanes;  // the rays of the packet, one bit each
    Walk ray[kPacketWidth];
    alignas(16) float tMin[kPacketWidth];
    alignas(16) float tMax[kPacketWidth];  // ray[l].tMax, for the lane test
    float tMaxAll;                         // the largest of them: the group test's far bound
    bool supported;
    uint32_t nodeTests, nodeBudget;        // group tests so far, and how many the packet may take
    bool overBudget;
};

// After a leaf: each ray's committed t into the packet's bounds.
static inline void refreshPacketBounds(PacketWalk& p) {
    float all = -INFINITY;
    for (uint32_t lanes = p.lanes; lanes != 0; lanes &= lanes - 1) {
        const uint32_t l = uint32_t(__builtin_ctz(lanes));
        p.tMax[l] = p.ray[l].tMax;
        all = p.tMax[l] > all ? p.tMax[l] : all;
    }
    p.tMaxAll = all;
}

using PacketStack = PacketScratch::Stack;

static inline void pushPacketChild(PacketStack& s, uint32_t& sp, format::ChildRef ref, float dist, uint32_t lanes) {
    if (sp < kStackCapacity) {  // the depth bound of the format makes overflow impossible for valid data
        s.ref[sp] = ref;
        s.dist[sp] = dist;
        s.lanes[sp] = lanes;
        ++sp;
    }
}

// Below this many rays a subtree is walked by each ray alone: the group test costs as much as a ray's node test and
// the lane tests more, so a packet of few rays only adds work ("fall back to single rays as lanes die").
constexpr uint32_t kPacketMinLanes = 4;

// The group tests a packet may take per ray before it is given up and its rays traced alone: a single ray takes
// some 10-40 node tests on the bench's meshes, so a packet over this budget has cost about what its rays alone
// would, and goes on costing more (rays that spread wider than the boxes: every node between them passes).
constexpr uint32_t kPacketNodeBudget = 24;

// Walks one structure from `root` for the rays `rootLanes` (in the space of L and f). The group test picks the
// children some ray may enter, the lane test which rays do; each child goes on with its rays: a leaf to
// leafFn(ref, lanes, sp), a subtree with fewer than kPacketMinLanes rays to aloneFn(ref, lanes), the others as a
// packet, the nearest entered directly and the rest pushed farthest first.
template <typename LeafFn, typename AloneFn>
static inline void walkPacket(PacketWalk& p, const format::Node* nodes, const PacketLanes& L, const PacketFrustum& f,
                              format::ChildRef root, uint32_t rootLanes, PacketStack& s, uint32_t base,
                              const LeafFn& leafFn, const AloneFn& aloneFn) {
    uint32_t sp = base;
    pushPacketChild(s, sp, root, f.tMin, rootLanes);
    while (sp > base && p.supported && !p.overBudget) {
        --sp;
        format::ChildRef ref = s.ref[sp];
        uint32_t lanes = s.lanes[sp];
        if (s.dist[sp] > p.tMaxAll * kFarSlack) continue;  // behind every ray's committed hit
        while (format::isInternal(ref)) {
            if (uint32_t(__builtin_popcount(lanes)) < kPacketMinLanes) {
                aloneFn(ref, lanes);
                ref = format::kEmptyRef;
                break;
            }
            if (++p.nodeTests > p.nodeBudget) {  // the packet costs more than its rays alone: give up
                p.overBudget = true;
                return;
            }
            const format::Node& node = nodes[format::nodeIndex(ref)];
            float entry[format::kNodeWidth];
            uint32_t mask = groupEntries(node, f, p.tMaxAll, entry);
            format::ChildRef refs[format::kNodeWidth];
            float dist[format::kNodeWidth];
            uint32_t childLanes[format::kNodeWidth];
            uint32_t hits = 0;
            for (; mask != 0; mask &= mask - 1) {
                const uint32_t i = uint32_t(__builtin_ctz(mask));
                const format::ChildRef child = node.child[i];
                if (child == format::kEmptyRef) continue;
                const uint32_t enter = lanesEntering(node, i, f, L, p.tMin, p.tMax, lanes);
                if (enter == 0) continue;
                if (format::isInternal(child)) prefetchNode(nodes + format::nodeIndex(child));
                uint32_t k = hits++;  // insertion by descending entry distance: the nearest last
                while (k > 0 && dist[k - 1] < entry[i]) {
                    dist[k] = dist[k - 1], refs[k] = refs[k - 1], childLanes[k] = childLanes[k - 1];
                    --k;
                }
                dist[k] = entry[i], refs[k] = child, childLanes[k] = enter;
            }
            if (hits == 0) {
                ref = format::kEmptyRef;
                break;
            }
            for (uint32_t k = 0; k + 1 < hits; ++k) pushPacketChild(s, sp, refs[k], dist[k], childLanes[k]);
            ref = refs[hits - 1];
            lanes = childLanes[hits - 1];
        }
        if (format::isLeaf(ref)) leafFn(ref, lanes, sp);
    }
}

// The triangle leaves of a bottom level: each ray that enters the leaf tests it alone. (Testing each triangle
// against 8 rays at a time instead was tried and was slower: most rays that enter a leaf miss all its triangles, and
// the single-ray test stops after one pass for those.)
struct PacketTriangleLeaves {
    PacketWalk& p;
    const std::byte* blas;
    void operator()(format::ChildRef leaf, uint32_t lanes, uint32_t) const {
        for (; lanes != 0; lanes &= lanes - 1) testTriangleLeaf<true>(p.ray[__builtin_ctz(lanes)], blas, leaf);
        refreshPacketBounds(p);
    }
};

// The instance leaves of the top level: the rays that enter an instance go on into its bottom level together when
// their object-space rays still form a packet, and alone otherwise.
struct PacketInstanceLeaves {
    PacketWalk& p;
    PacketStack& stack;
    KernelScratch& single;
    BlasResolver resolver;
    const format::InstanceRecord* instances;

    // The rays `lanes` each alone through `subtree` of bottom level `blas`, in their object space.
    void walkAlone(const std::byte* blas, format::ChildRef subtree, uint32_t lanes) const {
        for (; lanes != 0; lanes &= lanes - 1) {
            Walk& w = p.ray[__builtin_ctz(lanes)];
            walkTree(w, format::nodes(blas), w.objectRay, subtree, single, 0,
                     TriangleLeaves<true>{w, blas});
        }
        refreshPacketBounds(p);
    }

    void operator()(format::ChildRef leaf, uint32_t lanes, uint32_t sp) const {
        const uint32_t cullMask = p.ray[__builtin_ctz(lanes)].cullMask, flags = p.ray[__builtin_ctz(lanes)].flags;
        for (uint64_t i = format::leafFirst(leaf), end = i + format::leafCount(leaf); i < end; ++i) {
            const format::InstanceRecord& inst = instances[i];
            if (!instanceVisible(inst, cullMask)) continue;
            const std::byte* blas = resolveCached(single, resolver, inst.reference);
            const format::Header* h = walkableBottomLevel(blas, flags, p.supported);
            if (!p.supported) return;
            if (!h) continue;
            for (uint32_t m = lanes; m != 0; m &= m - 1) enterInstance(p.ray[__builtin_ctz(m)], inst);
            PacketLanes L;
            PacketFrustum f;
            const auto objectRay = [&](uint32_t l) -> const ShearedRay& { return p.ray[l].objectRay; };
            if (uint32_t(__builtin_popcount(lanes)) >= kPacketMinLanes && packetFrustum(objectRay, lanes, p.tMin, L, f)) {
                walkPacket(p, format::nodes(blas), L, f, h->root, lanes, stack, sp,
                           PacketTriangleLeaves{p, blas},
                           [&](format::ChildRef subtree, uint32_t alone) { walkAlone(blas, subtree, alone); });
            } else {
                walkAlone(blas, h->root, lanes);
            }
        }
    }
};

static bool tracePacketWith(const std::byte* topLevel, BlasResolver resolver, const KernelRay* rays, uint32_t count,
                            PacketScratch& s, QueryHit* hits, uint32_t& tied) {
    tied = 0;
    for (uint32_t l = 0; l < count; ++l) {
        hits[l].type = kCommittedNone;  // the other fields are written with a hit
        hits[l].t = rays[l].tMax;
    }
    const format::Header* top = traversableStructure(topLevel, format::StructureType::TopLevel);
    if (!top) return true;  // a null acceleration structure: every ray misses
    if (motion::isMotionBuild(top->buildFlags) || count == 0 || count > kPacketWidth) return false;
    PacketWalk p;
    p.lanes = (1u << count) - 1u;
    p.supported = true;
    p.nodeTests = 0;
    p.nodeBudget = kPacketNodeBudget * count;
    p.overBudget = false;
    for (uint32_t l = 0; l < count; ++l) {
        startWalk(p.ray[l], rays[l], hits[l]);
        prepareBoxRay(p.ray[l].worldRay, rays[l].origin, rays[l].direction);  // the packet walks the top level
        p.tMin[l] = rays[l].tMin;
        // One packet shares the batch's flags and mask; terminate-on-first-hit rays keep the first hit they meet,
        // which depends on the order, so they never come here.
        if (rays[l].flags != rays[0].flags || rays[l].cullMask != rays[0].cullMask ||
            (rays[l].flags & kRayTerminateOnFirstHit))
            return false;
    }
    refreshPacketBounds(p);
    PacketLanes L;
    PacketFrustum f;
    const auto worldRay = [&](uint32_t l) -> const ShearedRay& { return p.ray[l].worldRay; };
    if (!packetFrustum(worldRay, p.lanes, p.tMin, L, f)) return false;
    // A top-level subtree that few rays enter: each walks it alone, with the single-ray kernel's instance leaves (a
    // bottom level that the kernel does not cover sets `supported`, and the whole packet is traced again alone).
    const auto topAlone = [&](format::ChildRef subtree, uint32_t lanes) {
        for (; lanes != 0 && p.supported; lanes &= lanes - 1) {
            Walk& w = p.ray[__builtin_ctz(lanes)];
            walkTree(w, format::nodes(topLevel), w.worldRay, subtree, s.single, 0,
                     InstanceLeaves<true>{w, s.single, resolver, format::instances(topLevel), p.supported});
        }
        refreshPacketBounds(p);
    };
    walkPacket(p, format::nodes(topLevel), L, f, top->root, p.lanes, s.stack, 0,
               PacketInstanceLeaves{p, s.stack, s.single, resolver, format::instances(topLevel)}, topAlone);
    if (!p.supported || p.overBudget) return false;
    for (uint32_t l = 0; l < count; ++l)
        if (p.ray[l].tied) tied |= 1u << l;
    return true;
}
