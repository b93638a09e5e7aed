#include "dexelmill/study/oracle.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "dexelmill/error.h"

namespace dexelmill {

namespace {

/// Most buckets along one axis of the oracle's grid.
constexpr int kMaxBucketsPerAxis = 64;

/// How far a point is outside the tool at a pose, in mm-like units: positive outside, <= 0 inside.
double outside(const Tool& tool, const Vec3& axis, const Vec3& q) {
    const double z = glm::dot(q, axis);
    const Vec3 radial = q - z * axis;
    const double rho = std::sqrt(glm::dot(radial, radial));
    const double below = tool.bottom() - z, above = z - tool.totalLength();
    if (below > 0 || above > 0) return std::max(below, above) + rho;
    return rho - tool.radiusAt(z);
}

}  // namespace

MachinedSolidOracle::MachinedSolidOracle(const Box& stock, const ToolPath& path, const ToolTable& tools,
                                         double resolution)
    : stock_(stock), step_(resolution / 4), tools_(tools) {
    if (!(step_ > 0)) throw Error("oracle resolution must be positive");
    for (const Move& m : path.moves) {
        const auto it = tools_.find(m.tool);
        if (it == tools_.end()) throw Error("move uses tool T" + std::to_string(m.tool) + ", which is not defined");
        const Tool& t = it->second;
        MoveRef r{m.start, m.end - m.start, glm::normalize(m.axis), &t, {}};
        // The tool's box at a pose: the axis segment padded by the largest radius.
        for (const Vec3& tip : {m.start, m.end}) {
            r.bounds.expand(tip + t.bottom() * r.axis);
            r.bounds.expand(tip + t.totalLength() * r.axis);
        }
        r.bounds = r.bounds.padded(t.maxRadius());
        if (r.bounds.overlaps(stock_)) moves_.push_back(r);
    }
    const Vec3 size = stock_.size();
    const double cell = std::max({size.x, size.y, size.z}) / kMaxBucketsPerAxis;
    for (int a = 0; a < 3; ++a) {
        nb_[a] = std::clamp(int(std::ceil(size[a] / cell)), 1, kMaxBucketsPerAxis);
        bucketSize_[a] = size[a] / nb_[a];
    }
    buckets_.resize(std::size_t(nb_[0]) * nb_[1] * nb_[2]);
    for (std::size_t i = 0; i < moves_.size(); ++i) {
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = bucketAlong(a, moves_[i].bounds.lo[a]);
            hi[a] = bucketAlong(a, moves_[i].bounds.hi[a]);
        }
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x)
                    buckets_[std::size_t(x) + std::size_t(nb_[0]) * (y + std::size_t(nb_[1]) * z)].push_back(
                        std::uint32_t(i));
    }
}

int MachinedSolidOracle::bucketAlong(int a, double v) const {
    // Clamped in double before the conversion: a move may reach 1e9 mm, far past int's range
    // of buckets.
    const double b = std::floor((v - stock_.lo[a]) / bucketSize_[a]);
    return int(std::clamp(b, 0.0, double(nb_[a] - 1)));
}

std::size_t MachinedSolidOracle::bucketOf(const Vec3& p) const {
    int idx[3];
    for (int a = 0; a < 3; ++a) idx[a] = bucketAlong(a, p[a]);
    return std::size_t(idx[0]) + std::size_t(nb_[0]) * (idx[1] + std::size_t(nb_[1]) * idx[2]);
}

bool MachinedSolidOracle::inSweep(const MoveRef& m, const Vec3& p) const {
    if (!m.bounds.contains(p)) return false;
    const Vec3 q0 = p - m.start;
    // Dense samples of u, then a golden-section refinement around the best one.
    const double len = std::sqrt(glm::dot(m.feed, m.feed));
    // 64-bit: a move across the stock from 1e9 mm away has more samples than int counts.
    const std::int64_t n = std::max<std::int64_t>(1, std::int64_t(std::ceil(len / step_)));
    double best = 1e300;
    std::int64_t bestK = 0;
    for (std::int64_t k = 0; k <= n; ++k) {
        const double g = outside(*m.tool, m.axis, q0 - (double(k) / double(n)) * m.feed);
        if (g <= 0) return true;
        if (g < best) {
            best = g;
            bestK = k;
        }
    }
    if (n == 1 && len == 0) return false;
    double a = double(std::max<std::int64_t>(bestK - 1, 0)) / double(n), b = double(std::min(bestK + 1, n)) / double(n);
    const double phi = 0.5 * (std::sqrt(5.0) - 1);
    double c = b - phi * (b - a), d = a + phi * (b - a);
    double gc = outside(*m.tool, m.axis, q0 - c * m.feed), gd = outside(*m.tool, m.axis, q0 - d * m.feed);
    for (int it = 0; it < 60 && (b - a) * len > 1e-9; ++it) {
        if (gc <= 0 || gd <= 0) return true;
        if (gc < gd) {
            b = d;
            d = c;
            gd = gc;
            c = b - phi * (b - a);
            gc = outside(*m.tool, m.axis, q0 - c * m.feed);
        } else {
            a = c;
            c = d;
            gc = gd;
            d = a + phi * (b - a);
            gd = outside(*m.tool, m.axis, q0 - d * m.feed);
        }
    }
    return std::min(gc, gd) <= 0;
}

bool MachinedSolidOracle::removed(const Vec3& p) const {
    if (!stock_.padded(1e-9).contains(p)) {
        for (const MoveRef& m : moves_)
            if (inSweep(m, p)) return true;
        return false;
    }
    for (std::uint32_t i : buckets_[bucketOf(p)])
        if (inSweep(moves_[i], p)) return true;
    return false;
}

}  // namespace dexelmill
