#include "hitfile.hpp"

#include "report.hpp"

#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace vb {
namespace {

constexpr char kMagic[8] = {'V', 'K', 'A', 'S', 'H', 'I', 'T', 'S'};
constexpr uint32_t kVersion = 1, kRecordSize = 25;
constexpr uint32_t kSectionTag = 0x54434553u;  // "SECT"
constexpr uint32_t kEndTag = 0x2E444E45u;      // "END."
constexpr uint32_t kMaxName = 4096;
constexpr uint64_t kFnvBasis = 14695981039346656037ull, kFnvPrime = 1099511628211ull;

uint64_t fnv(uint64_t h, const unsigned char* p, size_t n) {
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * kFnvPrime;
    return h;
}

uint32_t bits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}
float fromBits(uint32_t u) {
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

void put32(std::string& s, uint32_t v) {
    for (int k = 0; k < 4; ++k) s += char((v >> (8 * k)) & 0xFF);
}
void put64(std::string& s, uint64_t v) {
    for (int k = 0; k < 8; ++k) s += char((v >> (8 * k)) & 0xFF);
}
uint32_t get32(const unsigned char* p) {
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
uint64_t get64(const unsigned char* p) { return uint64_t(get32(p)) | uint64_t(get32(p + 4)) << 32; }

void putRecord(std::string& s, const Hit& h) {
    s += char(h.hit() ? 1 : 0);
    put32(s, uint32_t(h.hit() ? h.inst : -1));
    put32(s, uint32_t(h.hit() ? h.geom : -1));
    put32(s, uint32_t(h.hit() ? h.prim : -1));
    put32(s, h.hit() ? bits(h.t) : 0);
    put32(s, h.hit() ? bits(h.u) : 0);
    put32(s, h.hit() ? bits(h.v) : 0);
}

// The same record once written (a miss is stored canonically).
bool sameRecord(const Hit& a, const Hit& b) {
    if (a.hit() != b.hit()) return false;
    return !a.hit() || (a.inst == b.inst && a.geom == b.geom && a.prim == b.prim && bits(a.t) == bits(b.t) &&
                        bits(a.u) == bits(b.u) && bits(a.v) == bits(b.v));
}

// Reads exactly n bytes or throws, naming the file and what was being read.
class Input {
public:
    Input(std::ifstream& f, const std::string& path, std::streamoff size) : f_(f), path_(path), size_(size) {}
    void read(unsigned char* p, size_t n, const char* what) {
        if (std::streamoff(n) > size_ - pos_) fail(std::string("truncated: it ends inside ") + what);
        f_.read(reinterpret_cast<char*>(p), std::streamsize(n));
        if (!f_) fail(std::string("read error in ") + what);
        pos_ += std::streamoff(n);
    }
    [[noreturn]] void fail(const std::string& why) const {
        throw std::runtime_error("--compare-hits " + path_ + ": not a valid hit file (" + why + ", at byte " +
                                 std::to_string(pos_) + " of " + std::to_string(size_) + ")");
    }
    std::streamoff pos() const { return pos_; }
    std::streamoff left() const { return size_ - pos_; }

private:
    std::ifstream& f_;
    const std::string& path_;
    std::streamoff size_, pos_ = 0;
};

}  // namespace

uint64_t rayHash(const std::vector<VkasRay>& rays) {
    uint64_t h = kFnvBasis;
    for (const VkasRay& r : rays) {
        const float f[8] = {r.origin[0], r.origin[1], r.origin[2], r.tMin, r.direction[0], r.direction[1], r.direction[2], r.tMax};
        unsigned char b[32];
        for (int k = 0; k < 8; ++k) {
            const uint32_t u = bits(f[k]);
            for (int j = 0; j < 4; ++j) b[4 * k + j] = (u >> (8 * j)) & 0xFF;
        }
        h = fnv(h, b, sizeof b);
    }
    return h;
}

HitFileWriter::HitFileWriter(const std::string& path, const std::string& writer) : f_(path, std::ios::binary), path_(path) {
    if (!f_) throw std::runtime_error("--dump-hits: cannot open " + path + " for writing");
    std::string s(kMagic, sizeof kMagic);
    put32(s, kVersion), put32(s, kRecordSize), put32(s, uint32_t(writer.size()));
    s += writer;
    f_.write(s.data(), std::streamsize(s.size()));
}

void HitFileWriter::add(const std::string& scene, RayKind kind, const std::vector<VkasRay>& rays, const std::vector<Hit>& hits) {
    if (scene.empty() || scene.size() > kMaxName) throw std::runtime_error("--dump-hits: scene name too long: " + scene);
    std::string s;
    s.reserve(36 + scene.size() + kRecordSize * hits.size());
    put32(s, kSectionTag), put32(s, uint32_t(scene.size()));
    s += scene;
    put32(s, uint32_t(kind)), put64(s, hits.size()), put64(s, rayHash(rays));
    for (const Hit& h : hits) putRecord(s, h);
    put64(s, fnv(kFnvBasis, reinterpret_cast<const unsigned char*>(s.data()), s.size()));
    f_.write(s.data(), std::streamsize(s.size()));
    if (!f_) throw std::runtime_error("--dump-hits: write error on " + path_);
    ++sections_;
}

void HitFileWriter::finish() {
    std::string s;
    put32(s, kEndTag), put32(s, sections_);
    f_.write(s.data(), std::streamsize(s.size()));
    f_.close();
    if (!f_) throw std::runtime_error("--dump-hits: write error on " + path_);
}

HitFileReader::HitFileReader(const std::string& path) : f_(path, std::ios::binary), path_(path) {
    if (!f_) throw std::runtime_error("--compare-hits: cannot open " + path);
    f_.seekg(0, std::ios::end);
    const std::streamoff size = f_.tellg();
    f_.seekg(0);
    Input in(f_, path_, size);
    unsigned char head[20];
    in.read(head, sizeof head, "the header");
    if (std::memcmp(head, kMagic, sizeof kMagic) != 0) in.fail("no VKASHITS magic");
    if (get32(head + 8) != kVersion) in.fail("version " + std::to_string(get32(head + 8)) + ", expected 1");
    if (get32(head + 12) != kRecordSize) in.fail("record size " + std::to_string(get32(head + 12)) + ", expected 25");
    const uint32_t writerSize = get32(head + 16);
    if (writerSize > kMaxName) in.fail("writer description of " + std::to_string(writerSize) + " bytes");
    writer_.resize(writerSize);
    in.read(reinterpret_cast<unsigned char*>(writer_.data()), writerSize, "the writer description");
    std::vector<unsigned char> buf;
    for (;;) {
        unsigned char tag[8];
        in.read(tag, 4, "a section tag (no trailer)");
        if (get32(tag) == kEndTag) {
            in.read(tag + 4, 4, "the trailer");
            if (get32(tag + 4) != sections_.size())
                in.fail("the trailer counts " + std::to_string(get32(tag + 4)) + " sections, the file holds " +
                        std::to_string(sections_.size()));
            if (in.left() != 0) in.fail(std::to_string(in.left()) + " bytes after the trailer");
            break;
        }
        if (get32(tag) != kSectionTag) in.fail("expected a section or the trailer");
        uint64_t sum = fnv(kFnvBasis, tag, 4);
        in.read(tag + 4, 4, "a section header");
        sum = fnv(sum, tag + 4, 4);
        const uint32_t nameSize = get32(tag + 4);
        if (nameSize == 0 || nameSize > kMaxName) in.fail("a scene name of " + std::to_string(nameSize) + " bytes");
        Section s;
        s.scene.resize(nameSize);
        in.read(reinterpret_cast<unsigned char*>(s.scene.data()), nameSize, "a scene name");
        sum = fnv(sum, reinterpret_cast<const unsigned char*>(s.scene.data()), nameSize);
        unsigned char fields[20];
        in.read(fields, sizeof fields, "a section header");
        sum = fnv(sum, fields, sizeof fields);
        const uint32_t kind = get32(fields);
        if (kind > 2) in.fail("ray kind " + std::to_string(kind));
        s.kind = RayKind(kind);
        s.rays = get64(fields + 4), s.hash = get64(fields + 12);
        if (s.rays > uint64_t(in.left()) / kRecordSize) in.fail("truncated: " + std::to_string(s.rays) + " records do not fit");
        s.offset = in.pos();
        constexpr size_t kChunk = 1 << 16;
        buf.resize(kChunk * kRecordSize);
        for (uint64_t done = 0; done < s.rays;) {
            const size_t n = size_t(std::min<uint64_t>(kChunk, s.rays - done));
            in.read(buf.data(), n * kRecordSize, "the records");
            for (size_t i = 0; i < n; ++i)
                if (buf[i * kRecordSize] > 1) in.fail("a record's hit byte is neither 0 nor 1");
            sum = fnv(sum, buf.data(), n * kRecordSize);
            done += n;
        }
        unsigned char check[8];
        in.read(check, 8, "a section checksum");
        if (get64(check) != sum) in.fail("the checksum of section '" + s.scene + "', " + rayKindName(s.kind) + " rays, does not match");
        sections_.push_back(std::move(s));
    }
}

HitFileReader::Section* HitFileReader::take(const std::string& scene, RayKind kind) {
    for (Section& s : sections_)
        if (!s.used && s.scene == scene && s.kind == kind) {
            s.used = true;
            return &s;
        }
    return nullptr;
}

std::vector<Hit> HitFileReader::read(const Section& s) {
    std::vector<unsigned char> buf(size_t(s.rays) * kRecordSize);
    f_.clear();
    f_.seekg(s.offset);
    f_.read(reinterpret_cast<char*>(buf.data()), std::streamsize(buf.size()));
    if (!f_) throw std::runtime_error("--compare-hits " + path_ + ": read error (the file changed during the run?)");
    std::vector<Hit> hits(size_t(s.rays));
    for (size_t i = 0; i < hits.size(); ++i) {
        const unsigned char* p = &buf[i * kRecordSize];
        Hit& h = hits[i];
        if (p[0] == 0) continue;  // a miss: Hit{}
        h.inst = int32_t(get32(p + 1)), h.geom = int32_t(get32(p + 5)), h.prim = int32_t(get32(p + 9));
        h.t = fromBits(get32(p + 13)), h.u = fromBits(get32(p + 17)), h.v = fromBits(get32(p + 21));
        if (h.prim < 0)
            throw std::runtime_error("--compare-hits " + path_ + ": a hit with primitive index " + std::to_string(h.prim) +
                                     " (ray " + std::to_string(i) + " of '" + s.scene + "', " + rayKindName(s.kind) + ")");
    }
    return hits;
}

HitComparison compareHitSets(const std::vector<VkasRay>& rays, const std::vector<Hit>& now, const std::vector<Hit>& before,
                             bool anyHit, const Judge& judge, unsigned threads) {
    HitComparison c;
    c.rays = rays.size();
    std::vector<size_t> other;
    for (size_t i = 0; i < rays.size(); ++i) {
        if (sameRecord(now[i], before[i])) ++c.identical;
        else other.push_back(i);
    }
    // The oracle decides the rest. A tie: another primitive at the same t within the agreement tolerance (each
    // triangle checked to lie at its t), or both answers acceptable. Any hits that both name a triangle need no
    // full trace.
    std::vector<char> tie(other.size(), 0);
    std::vector<Judgement> verdicts(other.size());
    parallelFor(threads, other.size(), 1, [&](size_t b, size_t e) {
        for (size_t d = b; d < e; ++d) {
            const size_t i = other[d];
            const bool sameT = !anyHit && classify(rays[i], now[i], before[i], false, Hit{}) == Category::Tie;
            if ((sameT || (anyHit && now[i].hit() && before[i].hit())) && judge.hitsTriangle(rays[i], now[i]) &&
                judge.hitsTriangle(rays[i], before[i])) {
                tie[d] = 1;
                continue;
            }
            verdicts[d] = judge.judge(rays[i], now[i], before[i], anyHit, true);
            tie[d] = verdicts[d].vkasOk && verdicts[d].embreeOk;
        }
    });
    for (size_t d = 0; d < other.size(); ++d) {
        if (tie[d]) {
            ++c.ties;
        } else {
            c.different.push_back(other[d]);
            c.verdicts.push_back(std::move(verdicts[d]));
        }
    }
    return c;
}

std::string hitDifferenceText(const char* kind, size_t index, const VkasRay& r, const Hit& now, const Hit& before,
                              const Judgement& j, bool anyHit) {
    auto hitText = [](const Hit& h) {
        char b[160];
        if (!h.hit()) return std::string("miss");
        std::snprintf(b, sizeof b, "inst %d geom %d prim %d t %a (%.9g) uv (%a, %a)", h.inst, h.geom, h.prim, h.t, h.t, h.u,
                      h.v);
        return std::string(b);
    };
    char buf[600];
    std::snprintf(buf, sizeof buf, "%s ray %zu: origin (%a, %a, %a) direction (%a, %a, %a) t [%a, %a] = origin (%.9g, "
                  "%.9g, %.9g) direction (%.9g, %.9g, %.9g) t [%.9g, %.9g]",
                  kind, index, r.origin[0], r.origin[1], r.origin[2], r.direction[0], r.direction[1], r.direction[2], r.tMin,
                  r.tMax, r.origin[0], r.origin[1], r.origin[2], r.direction[0], r.direction[1], r.direction[2], r.tMin, r.tMax);
    const std::string pad = "\n      ";
    const char* mode = anyHit ? "any hit" : "closest";
    const char* verdict = j.vkasOk ? "this build acceptable, the file's NOT"
                          : j.embreeOk ? "the file's acceptable, this build's NOT"
                                       : "UNEXPLAINED: the oracle accepts neither";
    return std::string(buf) + pad + "this build, " + mode + ": " + hitText(now) + pad + "  the oracle: " + j.vkas + pad +
           "the file, " + mode + ": " + hitText(before) + pad + "  the oracle: " + j.embree + pad + "oracle: " + j.oracle +
           pad + "verdict: " + verdict;
}

}  // namespace vb
