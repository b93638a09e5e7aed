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

/// Most poses a turning move's box is taken from.
constexpr int kMaxBoxPoses = 4096;

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
        MoveRef r{m.start, m.end - m.start, glm::normalize(m.axis), &t, {}, nullptr, 0.0};
        // The tool's box at a pose: the axis segment padded by the largest radius.
        const auto addPose = [&](const Vec3& tip, const Vec3& axis) {
            r.bounds.expand(tip + t.bottom() * axis);
            r.bounds.expand(tip + t.totalLength() * axis);
        };
        if (m.turns()) {
            // Poses at u_k = (k + 1/2) / n: every pose is within speed / (2 n) of one of them.
            r.law = std::make_shared<const MotionLaw>(m);
            r.speed = r.law->speedBound(std::hypot(std::max(std::abs(t.bottom()), t.totalLength()), t.maxRadius()));
            const int n = int(std::clamp(std::ceil(r.speed / t.maxRadius()), 1.0, double(kMaxBoxPoses)));
            for (int k = 0; k < n; ++k) {
                const ToolPose pose = r.law->pose((k + 0.5) / n);
                addPose(pose.tip, pose.axis);
            }
            r.bounds = r.bounds.padded(t.maxRadius() + r.speed / (2.0 * n));
        } else {
            addPose(m.start, r.axis);
            addPose(m.end, r.axis);
            r.bounds = r.bounds.padded(t.maxRadius());
        }
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
    // How far p is outside the tool at u.
    const auto at = [&](double u) {
        if (!m.law) return outside(*m.tool, m.axis, q0 - u * m.feed);
        const ToolPose pose = m.law->pose(u);
        return outside(*m.tool, pose.axis, p - pose.tip);
    };
    // Dense samples of u, no tool point moving more than a step between two, then a
    // golden-section refinement around the best one.
    const double travel = m.law ? m.speed : std::sqrt(glm::dot(m.feed, m.feed));
    // 64-bit: a move across the stock from 1e9 mm away has more samples than int counts.
    const std::int64_t n = std::max<std::int64_t>(1, std::int64_t(std::ceil(travel / step_)));
    double best = 1e300;
    std::int64_t bestK = 0;
    for (std::int64_t k = 0; k <= n; ++k) {
        const double g = at(double(k) / double(n));
        if (g <= 0) return true;
        if (g < best) {
            best = g;
            bestK = k;
        }
    }
    if (n == 1 && travel == 0) return false;
    double a = double(std::max<std::int64_t>(bestK - 1, 0)) / double(n), b = double(std::min(bestK + 1, n)) / double(n);
    const double phi = 0.5 * (std::sqrt(5.0) - 1);
    double c = b - phi * (b - a), d = a + phi * (b - a);
    double gc = at(c), gd = at(d);
    for (int it = 0; it < 60 && (b - a) * travel > 1e-9; ++it) {
        if (gc <= 0 || gd <= 0) return true;
        if (gc < gd) {
            b = d;
            d = c;
            gd = gc;
            c = b - phi * (b - a);
            gc = at(c);
        } else {
            a = c;
            c = d;
            gc = gd;
            d = a + phi * (b - a);
            gd = at(d);
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
