#include "meshes.hpp"

#include <cmath>
#include <map>

namespace vt {

Mesh icosphere(int subdivisions) {
    Mesh m;
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    const Float3 base[12] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                             {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    auto normalized = [](Float3 p) {
        const float l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        return Float3{p[0] / l, p[1] / l, p[2] / l};
    };
    for (const auto& p : base) m.positions.push_back(normalized(p));
    m.indices = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            const Float3 &pa = m.positions[a], &pb = m.positions[b];
            m.positions.push_back(normalized({(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2, (pa[2] + pb[2]) / 2}));
            const uint32_t idx = uint32_t(m.positions.size() - 1);
            mid[key] = idx;
            return idx;
        };
        std::vector<uint32_t> next;
        for (size_t i = 0; i < m.indices.size(); i += 3) {
            const uint32_t a = m.indices[i], b = m.indices[i + 1], c = m.indices[i + 2];
            const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        m.indices.swap(next);
    }
    return m;
}

Mesh terrain(int n, Rng& rng) {
    Mesh m;
    std::vector<float> h((n + 1) * (n + 1));
    // A few random waves plus noise.
    double a[4], fx[4], fy[4], ph[4];
    for (int k = 0; k < 4; ++k) {
        a[k] = rng.uniform(0.02, 0.15);
        fx[k] = rng.uniform(0.5, 6);
        fy[k] = rng.uniform(0.5, 6);
        ph[k] = rng.uniform(0, 6.28);
    }
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const double x = double(i) / n, y = double(j) / n;
            double z = rng.uniform(-0.01, 0.01);
            for (int k = 0; k < 4; ++k) z += a[k] * std::sin(fx[k] * x * 6.28 + fy[k] * y * 6.28 + ph[k]);
            m.positions.push_back({float(2 * x - 1), float(2 * y - 1), float(z)});
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const uint32_t v00 = j * (n + 1) + i, v10 = v00 + 1, v01 = v00 + (n + 1), v11 = v01 + 1;
            if (rng.coin())
                m.indices.insert(m.indices.end(), {v00, v10, v11, v00, v11, v01});
            else
                m.indices.insert(m.indices.end(), {v00, v10, v01, v10, v11, v01});
        }
    return m;
}

Mesh torusKnot(int segments, int sides, int p, int q) {
    Mesh m;
    const double R = 0.6, r = 0.12;
    auto curve = [&](double u) {
        const double cr = 0.5 * (2 + std::cos(q * u));
        return std::array<double, 3>{cr * std::cos(p * u) * R, cr * std::sin(p * u) * R, -0.5 * std::sin(q * u) * R};
    };
    for (int i = 0; i < segments; ++i) {
        const double u = 2 * M_PI * i / segments;
        const auto c = curve(u), c2 = curve(u + 1e-3);
        std::array<double, 3> tng{c2[0] - c[0], c2[1] - c[1], c2[2] - c[2]};
        std::array<double, 3> nrm{c2[0] + c[0], c2[1] + c[1], c2[2] + c[2]};
        std::array<double, 3> bin{tng[1] * nrm[2] - tng[2] * nrm[1], tng[2] * nrm[0] - tng[0] * nrm[2],
                                  tng[0] * nrm[1] - tng[1] * nrm[0]};
        nrm = {bin[1] * tng[2] - bin[2] * tng[1], bin[2] * tng[0] - bin[0] * tng[2], bin[0] * tng[1] - bin[1] * tng[0]};
        auto norm = [](std::array<double, 3>& v) {
            const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            for (double& x : v) x /= l;
        };
        norm(bin);
        norm(nrm);
        for (int j = 0; j < sides; ++j) {
            const double v = 2 * M_PI * j / sides;
            const double cx = -r * std::cos(v), cy = r * std::sin(v);
            m.positions.push_back({float(c[0] + cx * nrm[0] + cy * bin[0]), float(c[1] + cx * nrm[1] + cy * bin[1]),
                                   float(c[2] + cx * nrm[2] + cy * bin[2])});
        }
    }
    for (int i = 0; i < segments; ++i)
        for (int j = 0; j < sides; ++j) {
            const uint32_t a = i * sides + j, b = ((i + 1) % segments) * sides + j;
            const uint32_t c = ((i + 1) % segments) * sides + (j + 1) % sides, d = i * sides + (j + 1) % sides;
            m.indices.insert(m.indices.end(), {a, b, d, b, c, d});
        }
    return m;
}

Mesh triangleSoup(int count, Rng& rng, float size) {
    Mesh m;
    for (int i = 0; i < count; ++i) {
        const Float3 c{rng.uniformf(-1, 1), rng.uniformf(-1, 1), rng.uniformf(-1, 1)};
        for (int k = 0; k < 3; ++k) {
            m.positions.push_back(
                {c[0] + rng.uniformf(-size, size), c[1] + rng.uniformf(-size, size), c[2] + rng.uniformf(-size, size)});
            m.indices.push_back(uint32_t(m.positions.size() - 1));
        }
    }
    return m;
}

Mesh grid(int nx, int ny) {
    Mesh m;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) m.positions.push_back({float(i), float(j), 0.0f});
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const uint32_t a = j * (nx + 1) + i, b = a + 1, d = a + (nx + 1), c = d + 1;
            m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
        }
    return m;
}

Mesh randomSquareTessellation(int triangleTarget, Rng& rng, const TessellationLimits& limits) {
    Mesh m;
    auto z = [&]() { return rng.uniformf(-0.05f, 0.05f); };
    m.positions = {{0, 0, z()}, {1, 0, z()}, {1, 1, z()}, {0, 1, z()}};
    // Split the square around an off-centre interior point (the CTS uses 8 triangles around a pixel centre; 4 corners
    // plus 4 edge midpoints around one point give the same).
    m.positions.push_back({0.5f, 0.0f, z()});  // 4
    m.positions.push_back({1.0f, 0.5f, z()});  // 5
    m.positions.push_back({0.5f, 1.0f, z()});  // 6
    m.positions.push_back({0.0f, 0.5f, z()});  // 7
    m.positions.push_back({rng.uniformf(0.3f, 0.7f), rng.uniformf(0.3f, 0.7f), z()});  // 8
    const uint32_t ring[8] = {0, 4, 1, 5, 2, 6, 3, 7};
    for (int k = 0; k < 8; ++k) m.indices.insert(m.indices.end(), {8, ring[k], ring[(k + 1) % 8]});
    auto orient = [](const Float3& p0, const Float3& p1, const Float3& p2) {
        return (double(p1[0]) - p0[0]) * (double(p2[1]) - p0[1]) - (double(p1[1]) - p0[1]) * (double(p2[0]) - p0[0]);
    };
    // |grad z| of the height field over one triangle, and its smallest altitude (in the xy plane).
    auto slope = [&](const Float3& p0, const Float3& p1, const Float3& p2) {
        const double ax = double(p1[0]) - p0[0], ay = double(p1[1]) - p0[1], az = double(p1[2]) - p0[2];
        const double bx = double(p2[0]) - p0[0], by = double(p2[1]) - p0[1], bz = double(p2[2]) - p0[2];
        const double nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
        return std::sqrt(nx * nx + ny * ny) / std::fabs(nz);
    };
    auto altitude = [&](const Float3& p0, const Float3& p1, const Float3& p2) {
        const double area2 = std::fabs(orient(p0, p1, p2));
        double longest = 0;
        for (auto [a, b] : {std::pair{&p0, &p1}, std::pair{&p1, &p2}, std::pair{&p2, &p0}})
            longest = std::max(longest, std::hypot(double((*b)[0]) - (*a)[0], double((*b)[1]) - (*a)[1]));
        return area2 / longest;
    };
    while (int(m.triangleCount()) < triangleTarget) {
        // Split a random triangle at a random interior point into three.
        const size_t t = rng.below(uint32_t(m.triangleCount()));
        const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
        double w0 = rng.uniform(0.1, 1), w1 = rng.uniform(0.1, 1), w2 = rng.uniform(0.1, 1);
        const double s = w0 + w1 + w2;
        w0 /= s, w1 /= s, w2 /= s;
        const Float3 A = m.positions[a], B = m.positions[b], C = m.positions[c];
        const Float3 P{float(w0 * A[0] + w1 * B[0] + w2 * C[0]), float(w0 * A[1] + w1 * B[1] + w2 * C[1]), z()};
        // The point is rounded to float: make sure it is still well inside, so that the three new triangles keep
        // the (counter-clockwise) orientation and the mesh stays a height field without folds.
        const double whole = orient(A, B, C);
        if (!(whole > 1e-12) || !(orient(A, B, P) > 1e-3 * whole) || !(orient(B, C, P) > 1e-3 * whole) ||
            !(orient(C, A, P) > 1e-3 * whole))
            continue;
        // Bounded slopes and no slivers thinner than float rounding can resolve (see TessellationLimits).
        bool fits = true;
        for (auto [p0, p1] : {std::pair{&A, &B}, std::pair{&B, &C}, std::pair{&C, &A}})
            fits = fits && slope(*p0, *p1, P) <= limits.maxSlope && altitude(*p0, *p1, P) >= limits.minAltitude;
        if (!fits) continue;
        m.positions.push_back(P);
        const uint32_t p = uint32_t(m.positions.size() - 1);
        m.indices[3 * t + 2] = p;  // (a, b, p)
        m.indices.insert(m.indices.end(), {b, c, p, c, a, p});
    }
    return m;
}

Mesh closedFan(int n, Rng& rng) {
    Mesh m;
    m.positions.push_back({rng.uniformf(-0.02f, 0.02f), rng.uniformf(-0.02f, 0.02f), rng.uniformf(-0.2f, 0.2f)});
    std::vector<double> angles;
    for (int i = 0; i < n; ++i) angles.push_back(2 * M_PI * (i + rng.uniform(0.25, 0.75)) / n);
    for (int i = 0; i < n; ++i) {
        const double r = rng.uniform(0.5, 1.0);
        m.positions.push_back({float(r * std::cos(angles[i])), float(r * std::sin(angles[i])), rng.uniformf(-0.2f, 0.2f)});
    }
    for (int i = 0; i < n; ++i) m.indices.insert(m.indices.end(), {0u, uint32_t(1 + i), uint32_t(1 + (i + 1) % n)});
    return m;
}

}  // namespace vt
