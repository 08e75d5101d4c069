// The ray query's walk down the tree from a popped node (ray_query.cpp), included there once per instruction set
// (no include guard, on purpose), in a namespace that defines NodeRay, prepareNodeRay and nodeTest: the SSE2, AVX2 or
// AVX-512 node test (node_intersector_sse.hpp, node_intersector_avx2.hpp, node_intersector_avx512.hpp), which give identical results, so
// the query visits what the batch kernel visits either way.
//
// At each node the hit children are pushed, farthest first, except the nearest, which is entered at once: the same as
// pushing it last and popping it next (its entry distance passed the box test with the current tMax, so the pop's
// test would pass too; the batch kernel's walkTree does the same). Returns the leaf reached, or kEmptyRef when a node
// has no hit child.
inline ChildRef descend(RayQueryState& q, const Node* nodes, ChildRef ref, const ShearedRay& ray) {
    const NodeRay r = prepareNodeRay(ray);
    while (isInternal(ref)) {
        const Node& node = nodes[nodeIndex(ref)];
        float entry[kNodeWidth];
        float dist[kNodeWidth];
        ChildRef refs[kNodeWidth];
        const uint32_t hits = orderHitChildren(node, nodeTest(node, r, q.tMin, q.tMax, entry), entry, refs, dist);
        if (hits == 0) return kEmptyRef;
        for (uint32_t k = 0; k + 1 < hits; ++k) {  // (the walk of batch_kernel_body.hpp: prefetch what is pushed)
            if (isInternal(refs[k])) prefetchNode(nodes + nodeIndex(refs[k]));
            pushChild(q.stackRef, q.stackDist, q.sp, refs[k], dist[k]);
        }
        ref = refs[hits - 1];
    }
    return ref;
}
