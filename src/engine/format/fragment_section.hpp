// The fragment section of a bottom level of triangles built with PREFER_FAST_TRACE (docs/FORMAT.md, "Fragments").
//
// A spatial split (builders/spatial_split_builder.hpp) cuts a triangle's reference in two at a plane, so the triangle is
// stored in several records, each bounding only its part. Each such record has the kTriangleFragment flag and a
// region here: a half-open box [lower, upper) of space. The regions of one triangle's fragments partition all of
// space (they start as the whole space and each split divides one region at its plane), and a fragment reports a
// non-opaque candidate only where the hit point lies in its region. So however many of its fragments a ray visits, a
// triangle's candidate is reported by exactly one of them: duplicated references never show a ray the same primitive
// twice. (Opaque hits need no region: all fragments meet the ray at the same t, trace/hit_rules.hpp.)
//
// The section starts at Header::fragmentOffset, 16-byte aligned after the triangle array's tail, and holds
// Header::fragmentCount entries sorted by record index (strictly increasing).
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"

namespace vkas::format {

struct FragmentEntry {
    uint32_t record;    // the record's index in the triangle array (its leaf's first record + its lane)
    uint32_t reserved;  // 0
    float lower[3];     // the region: lower <= p < upper on every axis (an unbounded side is -inf / +inf)
    float upper[3];
};
static_assert(sizeof(FragmentEntry) == 32);

constexpr uint64_t kFragmentAlignment = 16;
// Where the section starts: the first aligned byte at or after the end of the triangle array (its tail included).
constexpr uint64_t fragmentSectionOffset(uint64_t recordsEnd) {
    return (recordsEnd + kFragmentAlignment - 1) / kFragmentAlignment * kFragmentAlignment;
}

inline const FragmentEntry* fragments(const std::byte* base) {
    return reinterpret_cast<const FragmentEntry*>(base + header(base)->fragmentOffset);
}

// The entry of `record`, or null when the section has none (a checked block always has one for a flagged record).
inline const FragmentEntry* findFragment(const std::byte* base, uint32_t record) {
    const FragmentEntry* e = fragments(base);
    uint32_t lo = 0, hi = header(base)->fragmentCount;
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (e[mid].record < record)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < header(base)->fragmentCount && e[lo].record == record ? &e[lo] : nullptr;
}

// Whether point p lies in the region of fragment `e`. Every fragment of a triangle is asked about the same point (the
// trace computes it once per ray and triangle: trace/fragment_hit_point.hpp), and the regions partition space, so
// exactly one of them holds it.
inline bool fragmentHolds(const FragmentEntry& e, const double p[3]) {
    for (int a = 0; a < 3; ++a)
        if (!(p[a] >= double(e.lower[a]) && p[a] < double(e.upper[a]))) return false;
    return true;
}

}  // namespace vkas::format
