#include "dexelmill/stock/dexel.h"

#include <algorithm>
#include <limits>

#include "dexelmill/error.h"

namespace dexelmill {

namespace {
constexpr std::size_t kMaxSegments = std::numeric_limits<std::uint16_t>::max();
}

void DexelTile::grow(int local, std::size_t needed) {
    if (needed > kMaxSegments) throw Error("a dexel would hold more than 65535 segments");
    if (offset_.empty()) {
        offset_.assign(kDexels + 1, 0);
        count_.assign(kDexels, 0);
    }
    const std::size_t cap = offset_[local + 1] - offset_[local];
    if (needed <= cap) return;
    // Rebuild the tile's array: every dexel keeps its segments, this one gets room for `needed`
    // plus one spare (a dexel that split once tends to split again), the others lose their slack.
    std::vector<Segment> segs;
    std::vector<std::uint32_t> offset(kDexels + 1);
    std::size_t total = 0;
    for (int i = 0; i < kDexels; ++i) total += (i == local) ? needed + 1 : count_[i];
    segs.resize(total);
    std::uint32_t at = 0;
    for (int i = 0; i < kDexels; ++i) {
        offset[i] = at;
        std::copy_n(segs_.data() + offset_[i], count_[i], segs.data() + at);
        at += std::uint32_t(i == local ? needed + 1 : count_[i]);
    }
    offset[kDexels] = at;
    segs_.swap(segs);
    offset_.swap(offset);
}

void DexelTile::releaseIfEmpty() {
    if (std::all_of(count_.begin(), count_.end(), [](std::uint16_t c) { return c == 0; })) {
        std::vector<std::uint32_t>().swap(offset_);
        std::vector<std::uint16_t>().swap(count_);
        std::vector<Segment>().swap(segs_);
    }
}

void DexelTile::setSegments(int local, const Segment* segs, std::size_t count) {
    if (count == 0 && offset_.empty()) return;
    grow(local, count);
    std::copy_n(segs, count, segs_.data() + offset_[local]);
    count_[local] = std::uint16_t(count);
    if (count == 0) releaseIfEmpty();
}

void DexelTile::assign(const std::uint16_t* counts, const Segment* segs) {
    offset_.assign(kDexels + 1, 0);
    count_.assign(counts, counts + kDexels);
    std::uint32_t at = 0;
    for (int i = 0; i < kDexels; ++i) {
        offset_[i] = at;
        at += counts[i];
    }
    offset_[kDexels] = at;
    segs_.assign(segs, segs + at);
    releaseIfEmpty();
}

template <class NormalAt>
double DexelTile::subtractImpl(int local, float lo, float hi, NormalAt&& normalAt) {
    if (offset_.empty() || !(lo < hi)) return 0.0;
    const std::size_t n = count_[local];
    Segment* s = segs_.data() + offset_[local];
    // First segment ending after lo, first segment starting at or after hi.
    const std::size_t first = std::size_t(
        std::partition_point(s, s + n, [lo](const Segment& g) { return g.hi <= lo; }) - s);
    const std::size_t last = std::size_t(
        std::partition_point(s + first, s + n, [hi](const Segment& g) { return g.lo < hi; }) - s);
    if (first == last) return 0.0;
    double removed = 0.0;
    for (std::size_t i = first; i < last; ++i)
        removed += double(std::min(s[i].hi, hi)) - double(std::max(s[i].lo, lo));
    // What survives of [first, last): a piece left of lo and a piece right of hi.
    Segment keep[2];
    std::size_t nKeep = 0;
    if (s[first].lo < lo) keep[nKeep++] = {s[first].lo, lo, s[first].nlo, normalAt(false)};
    if (s[last - 1].hi > hi) keep[nKeep++] = {hi, s[last - 1].hi, normalAt(true), s[last - 1].nhi};
    const std::size_t newCount = n - (last - first) + nKeep;
    if (newCount > n) {
        grow(local, newCount);
        s = segs_.data() + offset_[local];
    }
    // Shift the tail, then write the kept pieces.
    std::copy(s + last, s + n, s + first + nKeep);
    std::copy_n(keep, nKeep, s + first);
    count_[local] = std::uint16_t(newCount);
    if (newCount == 0) releaseIfEmpty();
    return removed;
}

double DexelTile::subtract(int local, float lo, float hi, PackedNormal atLo, PackedNormal atHi) {
    return subtractImpl(local, lo, hi, [&](bool atHiEnd) { return atHiEnd ? atHi : atLo; });
}

double DexelTile::subtract(int local, float lo, float hi, const Vec3& atLo, bool sharpLo, const Vec3& atHi,
                           bool sharpHi) {
    return subtractImpl(local, lo, hi, [&](bool atHiEnd) {
        return atHiEnd ? PackedNormal::pack(atHi, sharpHi) : PackedNormal::pack(atLo, sharpLo);
    });
}

double DexelTile::materialLength() const {
    double sum = 0.0;
    for (int i = 0; i < int(count_.size()); ++i)
        for (const Segment& g : segments(i)) sum += double(g.hi) - double(g.lo);
    return sum;
}

std::size_t DexelTile::segmentCount() const {
    std::size_t n = 0;
    for (std::uint16_t c : count_) n += c;
    return n;
}

std::size_t DexelTile::memoryBytes() const {
    return sizeof(*this) + offset_.capacity() * sizeof(std::uint32_t) +
           count_.capacity() * sizeof(std::uint16_t) + segs_.capacity() * sizeof(Segment);
}

DexelFamily::DexelFamily(Axis axis, int nb, int nc)
    : axis_(axis),
      nb_(nb),
      nc_(nc),
      tilesB_((nb + kTile - 1) / kTile),
      tilesC_((nc + kTile - 1) / kTile),
      tiles_(std::size_t(tilesB_) * std::size_t(tilesC_)) {}

double DexelFamily::materialLength() const {
    double sum = 0.0;
    for (const DexelTile& t : tiles_) sum += t.materialLength();
    return sum;
}

std::size_t DexelFamily::segmentCount() const {
    std::size_t n = 0;
    for (const DexelTile& t : tiles_) n += t.segmentCount();
    return n;
}

std::size_t DexelFamily::memoryBytes() const {
    std::size_t sum = sizeof(*this);
    for (const DexelTile& t : tiles_) sum += t.memoryBytes();
    return sum;
}

}  // namespace dexelmill
