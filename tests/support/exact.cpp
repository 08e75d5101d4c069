#include "exact.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

namespace vt {

// ---- Exact ------------------------------------------------------------------------------------------------------
namespace {
using Limbs = std::vector<uint32_t>;

Limbs shiftLeft(const Limbs& m, int64_t bits) {
    if (m.empty()) return m;
    const size_t limbs = size_t(bits / 32);
    const int rest = int(bits % 32);
    Limbs r(limbs, 0u);
    r.reserve(limbs + m.size() + 1);
    uint32_t carry = 0;
    for (uint32_t v : m) {
        r.push_back(rest ? (v << rest) | carry : v);
        carry = rest ? v >> (32 - rest) : 0;
    }
    if (carry) r.push_back(carry);
    return r;
}

int compareMag(const Limbs& a, const Limbs& b) {  // both trimmed
    if (a.size() != b.size()) return a.size() < b.size() ? -1 : 1;
    for (size_t i = a.size(); i-- > 0;)
        if (a[i] != b[i]) return a[i] < b[i] ? -1 : 1;
    return 0;
}

Limbs addMag(const Limbs& a, const Limbs& b) {
    Limbs r(std::max(a.size(), b.size()) + 1, 0u);
    uint64_t carry = 0;
    for (size_t i = 0; i < r.size(); ++i) {
        const uint64_t s = carry + (i < a.size() ? a[i] : 0u) + (i < b.size() ? b[i] : 0u);
        r[i] = uint32_t(s);
        carry = s >> 32;
    }
    return r;
}

Limbs subMag(const Limbs& a, const Limbs& b) {  // |a| >= |b|
    Limbs r(a.size(), 0u);
    int64_t borrow = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        int64_t d = int64_t(a[i]) - (i < b.size() ? int64_t(b[i]) : 0) - borrow;
        borrow = d < 0;
        if (d < 0) d += int64_t(1) << 32;
        r[i] = uint32_t(d);
    }
    assert(borrow == 0);
    return r;
}
}  // namespace

void Exact::trim() {
    while (!mag_.empty() && mag_.back() == 0) mag_.pop_back();
    size_t low = 0;
    while (low < mag_.size() && mag_[low] == 0) ++low;
    if (low) {
        mag_.erase(mag_.begin(), mag_.begin() + std::ptrdiff_t(low));
        exp_ += 32 * int64_t(low);
    }
    if (mag_.empty()) neg_ = false, exp_ = 0;
}

Exact::Exact(double v) {
    if (v == 0.0 || !std::isfinite(v)) return;
    int e = 0;
    const double f = std::frexp(std::fabs(v), &e);  // |v| = f 2^e, 0.5 <= f < 1
    const uint64_t m = uint64_t(std::ldexp(f, 53));  // exact: f has 53 significant bits at most
    neg_ = v < 0;
    mag_ = {uint32_t(m), uint32_t(m >> 32)};
    exp_ = int64_t(e) - 53;
    trim();
}

Exact Exact::operator-() const {
    Exact r = *this;
    if (!r.mag_.empty()) r.neg_ = !r.neg_;
    return r;
}

Exact operator+(const Exact& a, const Exact& b) {
    if (a.mag_.empty()) return b;
    if (b.mag_.empty()) return a;
    const int64_t e = std::min(a.exp_, b.exp_);
    Limbs ma = shiftLeft(a.mag_, a.exp_ - e), mb = shiftLeft(b.mag_, b.exp_ - e);
    Exact r;
    r.exp_ = e;
    if (a.neg_ == b.neg_) {
        r.mag_ = addMag(ma, mb);
        r.neg_ = a.neg_;
    } else {
        const int c = compareMag(ma, mb);
        if (c == 0) return Exact();
        r.mag_ = c > 0 ? subMag(ma, mb) : subMag(mb, ma);
        r.neg_ = c > 0 ? a.neg_ : b.neg_;
    }
    r.trim();
    return r;
}

Exact operator-(const Exact& a, const Exact& b) { return a + (-b); }

Exact operator*(const Exact& a, const Exact& b) {
    if (a.mag_.empty() || b.mag_.empty()) return Exact();
    Exact r;
    r.mag_.assign(a.mag_.size() + b.mag_.size(), 0u);
    for (size_t i = 0; i < a.mag_.size(); ++i) {
        uint64_t carry = 0;
        for (size_t j = 0; j < b.mag_.size(); ++j) {
            const uint64_t s = uint64_t(a.mag_[i]) * b.mag_[j] + r.mag_[i + j] + carry;
            r.mag_[i + j] = uint32_t(s);
            carry = s >> 32;
        }
        r.mag_[i + b.mag_.size()] = uint32_t(carry);
    }
    r.neg_ = a.neg_ != b.neg_;
    r.exp_ = a.exp_ + b.exp_;
    r.trim();
    return r;
}

double Exact::approx() const {
    double v = 0;
    for (size_t i = 0; i < mag_.size(); ++i) v += std::ldexp(double(mag_[i]), int(exp_ + 32 * int64_t(i)));
    return neg_ ? -v : v;
}

// ---- Crossings --------------------------------------------------------------------------------------------------
namespace {
using E3 = std::array<Exact, 3>;

E3 exactSub(const Float3& a, const Float3& b) {
    return {Exact(a[0]) - Exact(b[0]), Exact(a[1]) - Exact(b[1]), Exact(a[2]) - Exact(b[2])};
}
E3 exactCross(const E3& a, const E3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Exact exactDot(const E3& a, const E3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
E3 exactOf(const Float3& a) { return {Exact(a[0]), Exact(a[1]), Exact(a[2])}; }

// The sign of the edge function d . ((a - o) x (b - o)) of the line translated by (e, e^2, e^3): its value minus
// (e, e^2, e^3) . ((b - a) x d), so a zero takes the opposite sign of the first non-zero component of (b - a) x d.
// perturbed: the unperturbed value was zero.
int exactEdgeSign(const Float3& a, const Float3& b, const Float3& o, const Float3& d, bool& perturbed) {
    const E3 dd = exactOf(d);
    const int s = exactDot(dd, exactCross(exactSub(a, o), exactSub(b, o))).sign();
    if (s != 0) return s;
    perturbed = true;
    const E3 c = exactCross(exactSub(b, a), dd);
    for (const Exact& k : c)
        if (k.sign() != 0) return -k.sign();
    return 0;  // the edge is parallel to the ray: the triangle is edge-on
}

// The same edge function in double, with a bound on its error: 0 when the bound cannot decide the sign.
int filteredEdgeSign(const double A[3], const double B[3], const Float3& d) {
    const double cx = A[1] * B[2] - A[2] * B[1], cy = A[2] * B[0] - A[0] * B[2], cz = A[0] * B[1] - A[1] * B[0];
    const double e = double(d[0]) * cx + double(d[1]) * cy + double(d[2]) * cz;
    const double px = std::fabs(A[1] * B[2]) + std::fabs(A[2] * B[1]),
                 py = std::fabs(A[2] * B[0]) + std::fabs(A[0] * B[2]),
                 pz = std::fabs(A[0] * B[1]) + std::fabs(A[1] * B[0]);
    const double permanent = std::fabs(double(d[0])) * px + std::fabs(double(d[1])) * py + std::fabs(double(d[2])) * pz;
    // A and B carry one rounding each (the difference of two floats in double), then five more operations deep:
    // the error is below 10 * 2^-53 * permanent (plus underflow, excluded by the second test); 1e-14 is generous.
    if (permanent > 1e-250 && std::fabs(e) > 1e-14 * permanent) return e > 0 ? 1 : -1;
    return 0;
}

// Distance from the line (o, d) to the segment [a, b], measured perpendicular to d (double; for tolerances).
double lineSegmentDistance(const Float3& a, const Float3& b, const Float3& o, const Float3& d) {
    const double len = std::sqrt(double(d[0]) * d[0] + double(d[1]) * d[1] + double(d[2]) * d[2]);
    const double u[3] = {d[0] / len, d[1] / len, d[2] / len};
    double pa[3], pb[3];
    for (int k = 0; k < 3; ++k) pa[k] = double(a[k]) - o[k], pb[k] = double(b[k]) - o[k];
    const double sa = pa[0] * u[0] + pa[1] * u[1] + pa[2] * u[2], sb = pb[0] * u[0] + pb[1] * u[1] + pb[2] * u[2];
    for (int k = 0; k < 3; ++k) pa[k] -= sa * u[k], pb[k] -= sb * u[k];
    double e[3], ee = 0, ae = 0;
    for (int k = 0; k < 3; ++k) e[k] = pb[k] - pa[k], ee += e[k] * e[k], ae += pa[k] * e[k];
    const double s = ee > 0 ? std::clamp(-ae / ee, 0.0, 1.0) : 0.0;
    double dist2 = 0;
    for (int k = 0; k < 3; ++k) dist2 += (pa[k] + s * e[k]) * (pa[k] + s * e[k]);
    return std::sqrt(dist2);
}
}  // namespace

std::string ExactCount::str() const {
    std::ostringstream s;
    s << crossings.size() << " exact crossing(s) (" << front << " front, " << back << " back)";
    for (const ExactCrossing& c : crossings)
        s << " [" << c.triangle << (c.front ? " front" : " back") << (c.perturbed ? " perturbed" : "") << "]";
    if (nearSilhouette) s << "; within tolerance of a silhouette edge";
    if (nearBoundary) s << "; within tolerance of the open boundary";
    if (closestCriticalEdge < 1e300) s << "; nearest silhouette/boundary edge at " << closestCriticalEdge;
    return s.str();
}

ExactMeshOracle::ExactMeshOracle(const Mesh& mesh) : mesh_(mesh) {
    const size_t n = mesh.triangleCount();
    std::map<std::pair<uint32_t, uint32_t>, size_t> index;
    triangleEdges_.resize(n);
    boxes_.resize(n);
    for (int k = 0; k < 3; ++k) lo_[k] = 1e300, hi_[k] = -1e300;
    for (size_t t = 0; t < n; ++t) {
        std::array<double, 6>& box = boxes_[t];
        for (int k = 0; k < 3; ++k) box[k] = 1e300, box[k + 3] = -1e300;
        for (int j = 0; j < 3; ++j) {
            const Float3& p = mesh.positions[mesh.indices[3 * t + j]];
            for (int k = 0; k < 3; ++k) {
                box[k] = std::min(box[k], double(p[k]));
                box[k + 3] = std::max(box[k + 3], double(p[k]));
                lo_[k] = std::min(lo_[k], double(p[k]));
                hi_[k] = std::max(hi_[k], double(p[k]));
            }
            const auto key = std::minmax(mesh.indices[3 * t + j], mesh.indices[3 * t + (j + 1) % 3]);
            auto [it, fresh] = index.emplace(key, edges_.size());
            if (fresh) {
                edges_.push_back({key.first, key.second, {int32_t(t), -1}});
            } else {
                Edge& e = edges_[it->second];
                e.tri[1] = e.tri[1] == -1 ? int32_t(t) : -2;
            }
            triangleEdges_[t][size_t(j)] = uint32_t(it->second);
        }
    }
    cells_ = std::max(1, int(std::sqrt(double(n) / 2)));
    for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        grid_[size_t(k)].resize(size_t(cells_) * size_t(cells_));
        auto cell = [&](double v, int axis) {
            const double span = hi_[axis] - lo_[axis];
            return span > 0 ? std::clamp(int((v - lo_[axis]) / span * cells_), 0, cells_ - 1) : 0;
        };
        for (size_t t = 0; t < n; ++t)
            for (int ci = cell(boxes_[t][size_t(i)], i); ci <= cell(boxes_[t][size_t(i) + 3], i); ++ci)
                for (int cj = cell(boxes_[t][size_t(j)], j); cj <= cell(boxes_[t][size_t(j) + 3], j); ++cj)
                    grid_[size_t(k)][size_t(ci) * size_t(cells_) + size_t(cj)].push_back(uint32_t(t));
    }
}

std::vector<uint32_t> ExactMeshOracle::near(const Float3& o, const Float3& d, double tolerance) const {
    // The dominant axis k of d; the line over the mesh's k range (widened by the tolerance) covers a box in the
    // other two axes: every triangle it crosses has its box there, and so has every edge within the tolerance
    // (the closest points of line and edge are at most `tolerance` apart).
    int k = 0;
    for (int a = 1; a < 3; ++a)
        if (std::fabs(d[a]) > std::fabs(d[k])) k = a;
    std::vector<uint32_t> out;
    if (d[k] == 0) return out;
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    const double pad = tolerance * 2 + 1e-9 * (1 + std::fabs(o[0]) + std::fabs(o[1]) + std::fabs(o[2]));
    const double t0 = (lo_[k] - pad - o[k]) / d[k], t1 = (hi_[k] + pad - o[k]) / d[k];
    double lo[2], hi[2];
    const int axes[2] = {i, j};
    for (int a = 0; a < 2; ++a) {
        const double u = o[axes[a]] + t0 * d[axes[a]], v = o[axes[a]] + t1 * d[axes[a]];
        lo[a] = std::min(u, v) - pad;
        hi[a] = std::max(u, v) + pad;
        if (hi[a] < lo_[axes[a]] || lo[a] > hi_[axes[a]]) return out;
    }
    auto cell = [&](double v, int axis) {
        const double span = hi_[axis] - lo_[axis];
        return span > 0 ? std::clamp(int((v - lo_[axis]) / span * cells_), 0, cells_ - 1) : 0;
    };
    std::vector<char> seen(mesh_.triangleCount(), 0);
    for (int ci = cell(lo[0], i); ci <= cell(hi[0], i); ++ci)
        for (int cj = cell(lo[1], j); cj <= cell(hi[1], j); ++cj)
            for (uint32_t t : grid_[size_t(k)][size_t(ci) * size_t(cells_) + size_t(cj)]) {
                const auto& b = boxes_[t];
                if (seen[t] || b[size_t(i) + 3] < lo[0] || b[size_t(i)] > hi[0] || b[size_t(j) + 3] < lo[1] ||
                    b[size_t(j)] > hi[1])
                    continue;
                seen[t] = 1;
                out.push_back(t);
            }
    std::sort(out.begin(), out.end());
    return out;
}

int ExactMeshOracle::facing(uint32_t t, const Float3& d) const {
    const auto& P = mesh_.positions;
    const Float3 &a = P[mesh_.indices[3 * t]], &b = P[mesh_.indices[3 * t + 1]], &c = P[mesh_.indices[3 * t + 2]];
    const double e1[3] = {double(b[0]) - a[0], double(b[1]) - a[1], double(b[2]) - a[2]};
    const double e2[3] = {double(c[0]) - a[0], double(c[1]) - a[1], double(c[2]) - a[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double nd = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    const double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double dl = std::sqrt(double(d[0]) * d[0] + double(d[1]) * d[1] + double(d[2]) * d[2]);
    return std::fabs(nd) > 1e-9 * nn * dl ? (nd > 0 ? 1 : -1) : 0;
}

int ExactMeshOracle::edgeSigns(const uint32_t idx[3], const std::array<double, 3> rel[3], const Float3& o,
                               const Float3& d, bool& perturbed) const {
    const auto& P = mesh_.positions;
    int sign[3];
    bool certain = true;
    for (int k = 0; k < 3; ++k) {
        sign[k] = filteredEdgeSign(rel[k].data(), rel[(k + 1) % 3].data(), d);
        certain = certain && sign[k] != 0;
    }
    // Two signs known to differ: not crossed, whatever the third.
    for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j)
            if (sign[k] > 0 && sign[j] < 0) return 0;
    if (!certain)
        for (int k = 0; k < 3; ++k)
            if (sign[k] == 0) sign[k] = exactEdgeSign(P[idx[k]], P[idx[(k + 1) % 3]], o, d, perturbed);
    return sign[0] == sign[1] && sign[1] == sign[2] ? sign[0] : 0;
}

bool ExactMeshOracle::crossesOrNear(uint32_t t, const Float3& o, const Float3& d, double tolerance) const {
    const auto& P = mesh_.positions;
    const uint32_t idx[3] = {mesh_.indices[3 * t], mesh_.indices[3 * t + 1], mesh_.indices[3 * t + 2]};
    for (int k = 0; k < 3; ++k)
        if (lineSegmentDistance(P[idx[k]], P[idx[(k + 1) % 3]], o, d) <= tolerance) return true;
    std::array<double, 3> rel[3];
    for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) rel[j][k] = double(P[idx[j]][k]) - double(o[k]);
    bool perturbed = false;
    return edgeSigns(idx, rel, o, d, perturbed) != 0;
}

ExactCount ExactMeshOracle::count(const Float3& o, const Float3& d, float tMin, float tMax, double tolerance) const {
    ExactCount out;
    const auto& P = mesh_.positions;
    const E3 dd = exactOf(d);
    const std::vector<uint32_t> candidates = near(o, d, tolerance);
    std::set<uint32_t> edges;
    for (uint32_t t : candidates) {
        const uint32_t idx[3] = {mesh_.indices[3 * t], mesh_.indices[3 * t + 1], mesh_.indices[3 * t + 2]};
        edges.insert(triangleEdges_[t].begin(), triangleEdges_[t].end());
        std::array<double, 3> rel[3];
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) rel[j][k] = double(P[idx[j]][k]) - double(o[k]);
        bool perturbed = false;
        if (edgeSigns(idx, rel, o, d, perturbed) == 0) continue;
        // tMin < t < tMax with t = N . (v0 - o) / (N . d), exactly.
        const E3 v0 = exactSub(P[idx[0]], o);
        const E3 n = exactCross(exactSub(P[idx[1]], P[idx[0]]), exactSub(P[idx[2]], P[idx[0]]));
        const Exact num = exactDot(n, v0), den = exactDot(n, dd);
        const int ds = den.sign();
        if (ds == 0) continue;
        if ((num - Exact(tMin) * den).sign() * ds <= 0 || (Exact(tMax) * den - num).sign() * ds <= 0) continue;
        ExactCrossing c;
        c.triangle = t;
        c.front = ds < 0;
        c.perturbed = perturbed;
        out.anyPerturbed = out.anyPerturbed || perturbed;
        (c.front ? out.front : out.back) += 1;
        out.crossings.push_back(c);
    }
    for (uint32_t ei : edges) {
        const Edge& e = edges_[ei];
        const bool boundary = e.tri[1] == -1;
        const bool silhouette =
            !boundary && (e.tri[1] == -2 || facing(uint32_t(e.tri[0]), d) * facing(uint32_t(e.tri[1]), d) != 1);
        if (!boundary && !silhouette) continue;
        const double dist = lineSegmentDistance(P[e.a], P[e.b], o, d);
        out.closestCriticalEdge = std::min(out.closestCriticalEdge, dist);
        if (dist <= tolerance) (boundary ? out.nearBoundary : out.nearSilhouette) = true;
    }
    return out;
}

}  // namespace vt
