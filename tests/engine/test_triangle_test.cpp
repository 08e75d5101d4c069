// The watertight ray / triangle test on its own (trace/triangle_intersector.hpp) against a double-precision oracle:
// random triangles and rays; where the oracle is clear (the ray passes the triangle's edges by a margin), the
// test must agree on hit or miss, and on a hit its t and barycentrics must match the oracle's closely.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/trace/ray.hpp"
#include "engine/trace/triangle_intersector.hpp"
#include "vkas_test.hpp"

namespace {

struct TriangleTest : ::testing::Test {
    uint64_t seed = vt::chooseSeed();
    vt::Rng rng{seed};
    void SetUp() override {
        std::cout << "[   SEED   ] VKAS_TEST_SEED=" << seed << std::endl;
        RecordProperty("VKAS_TEST_SEED", std::to_string(seed));
    }
};

// Möller-Trumbore in double: t, barycentrics (b, c) and the smallest edge distance in units of the barycentrics.
bool oracle(const float o[3], const float d[3], const float v0[3], const float v1[3], const float v2[3], double& t,
            double& b, double& c, double& det) {
    double e1[3], e2[3], p[3], s[3], q[3];
    for (int k = 0; k < 3; ++k) e1[k] = double(v1[k]) - v0[k], e2[k] = double(v2[k]) - v0[k], s[k] = double(o[k]) - v0[k];
    p[0] = d[1] * e2[2] - double(d[2]) * e2[1];
    p[1] = d[2] * e2[0] - double(d[0]) * e2[2];
    p[2] = d[0] * e2[1] - double(d[1]) * e2[0];
    det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0.0) return false;
    b = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
    q[0] = s[1] * e1[2] - s[2] * e1[1];
    q[1] = s[2] * e1[0] - s[0] * e1[2];
    q[2] = s[0] * e1[1] - s[1] * e1[0];
    c = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
    t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
    return true;
}

TEST_F(TriangleTest, agrees_with_a_double_precision_oracle_away_from_edges) {
    int hits = 0, misses = 0;
    for (int iter = 0; iter < 200000; ++iter) {
        float v[3][3], o[3], d[3];
        for (auto& p : v)
            for (float& x : p) x = rng.uniformf(-4.0f, 4.0f);
        for (int k = 0; k < 3; ++k) o[k] = rng.uniformf(-8.0f, 8.0f), d[k] = rng.uniformf(-1.0f, 1.0f);
        double t, b, c, det;
        if (!oracle(o, d, v[0], v[1], v[2], t, b, c, det)) continue;
        const double a = 1.0 - b - c;
        const double margin = std::min({a, b, c});
        if (std::fabs(margin) < 1e-3) continue;  // near an edge: the watertightness tests decide there
        vkas::ShearedRay r;
        vkas::prepareShearedRay(r, o, d);
        vkas::TriangleHit h;
        const bool got = vkas::intersectTriangle(r, v[0], v[1], v[2], h);
        ASSERT_EQ(got, margin > 0.0) << "iteration " << iter << " margin " << margin;
        if (!got) {
            ++misses;
            continue;
        }
        ++hits;
        const double scale = std::max(1.0, std::fabs(t));
        ASSERT_NEAR(h.t, t, 1e-3 * scale) << "iteration " << iter;
        ASSERT_NEAR(h.b, b, 1e-3) << "iteration " << iter;
        ASSERT_NEAR(h.c, c, 1e-3) << "iteration " << iter;
        // frontFace: the ray sees the vertices counter-clockwise, i.e. it runs against the normal e1 x e2, where
        // Moller-Trumbore's determinant e1 . (d x e2) = -d . (e1 x e2) is positive.
        ASSERT_EQ(h.frontFace, det > 0.0) << "iteration " << iter;
    }
    EXPECT_GT(hits, 1000);
    EXPECT_GT(misses, 1000);
}

// A ray through a shared edge of two triangles (a quad split on its diagonal) is reported by exactly one.
TEST_F(TriangleTest, a_shared_edge_is_hit_exactly_once) {
    int through = 0;
    for (int iter = 0; iter < 20000; ++iter) {
        float p[4][3];
        for (auto& q : p) q[0] = rng.uniformf(-2, 2), q[1] = rng.uniformf(-2, 2), q[2] = rng.uniformf(-0.5f, 0.5f);
        const float s = rng.uniformf(0.0f, 1.0f);
        float o[3], d[3] = {rng.uniformf(-0.2f, 0.2f), rng.uniformf(-0.2f, 0.2f), -1.0f};
        // A point on the shared edge p0-p2, then the ray origin above it along -d.
        float e[3];
        for (int k = 0; k < 3; ++k) e[k] = p[0][k] + s * (p[2][k] - p[0][k]);
        for (int k = 0; k < 3; ++k) o[k] = e[k] - 3.0f * d[k];
        vkas::ShearedRay r;
        vkas::prepareShearedRay(r, o, d);
        vkas::TriangleHit h0, h1;
        const bool a = vkas::intersectTriangle(r, p[0], p[1], p[2], h0);
        const bool b = vkas::intersectTriangle(r, p[0], p[2], p[3], h1);
        double t, bb, cc, det0, det1;
        // Only quads whose two halves face the same way and lie on opposite sides of the edge (a proper quad).
        if (!oracle(o, d, p[0], p[1], p[2], t, bb, cc, det0) || !oracle(o, d, p[0], p[2], p[3], t, bb, cc, det1))
            continue;
        if ((det0 > 0) != (det1 > 0)) continue;
        ASSERT_LE(int(a) + int(b), 1) << "iteration " << iter << ": both triangles report the shared edge";
        // Away from the edge's endpoints the ray passes the (rounded) edge point inside the quad: one reports it.
        if (s > 0.01f && s < 0.99f) {
            ASSERT_EQ(int(a) + int(b), 1) << "iteration " << iter << ": a ray through the shared edge misses both";
            ++through;
        }
    }
    EXPECT_GT(through, 1000);
}

}  // namespace
