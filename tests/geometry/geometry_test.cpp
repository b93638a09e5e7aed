#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "dexelmill/error.h"
#include "dexelmill/geometry/frame.h"
#include "dexelmill/geometry/packed_normal.h"
#include "dexelmill/geometry/types.h"

using namespace dexelmill;

TEST_CASE("intervals: empty, hull and intersection", "[geometry]") {
    CHECK(Interval().isEmpty());
    CHECK(Interval::empty().length() == 0);
    const Interval a{1, 3}, b{2, 5}, c{6, 7};
    CHECK(a.hull(b).lo == 1);
    CHECK(a.hull(b).hi == 5);
    CHECK(a.intersect(c).isEmpty());
    CHECK(a.intersect(b).lo == 2);
    CHECK(a.hull(Interval::empty()).hi == 3);
    CHECK(Interval::empty().hull(c).lo == 6);
}

TEST_CASE("boxes: expand, overlap, padding", "[geometry]") {
    Box b;
    CHECK(b.isEmpty());
    b.expand(Vec3(1, 2, 3));
    b.expand(Vec3(-1, 0, 5));
    CHECK(b.size() == Vec3(2, 2, 2));
    CHECK(b.contains(Vec3(0, 1, 4)));
    CHECK_FALSE(b.contains(Vec3(0, 1, 6)));
    CHECK(b.overlaps(Box{Vec3(1, 2, 5), Vec3(9, 9, 9)}));  // touching counts
    CHECK_FALSE(b.overlaps(Box{Vec3(1.1, 0, 3), Vec3(9, 9, 9)}));
    CHECK(b.padded(1).volume() == Approx(64));
}

TEST_CASE("tool frame: orthonormal, e perpendicular to the feed, feed decomposes", "[geometry]") {
    std::mt19937_64 rng(11);
    std::normal_distribution<double> n;
    for (int i = 0; i < 1000; ++i) {
        const Vec3 axis(n(rng), n(rng), n(rng)), feed(n(rng), n(rng), n(rng));
        const ToolFrame fr = ToolFrame::make(axis, feed);
        CHECK_FALSE(fr.plunge);
        CHECK(glm::length(fr.n) == Approx(1));
        CHECK(glm::length(fr.e) == Approx(1));
        CHECK(glm::length(fr.d) == Approx(1));
        CHECK(glm::dot(fr.e, feed) == Approx(0).margin(1e-12));
        CHECK(glm::dot(fr.d, fr.n) == Approx(0).margin(1e-12));
        // f = (d.f) d + (n.f) n
        const Vec3 back = glm::dot(fr.d, feed) * fr.d + glm::dot(fr.n, feed) * fr.n;
        CHECK(glm::length(back - feed) == Approx(0).margin(1e-12));
        CHECK(glm::dot(fr.d, feed) >= 0);
    }
}

TEST_CASE("tool frame: plunge, retract and zero feed leave e undefined", "[geometry]") {
    for (const Vec3& feed : {Vec3(0, 0, -5), Vec3(0, 0, 3), Vec3(0.0)}) {
        const ToolFrame fr = ToolFrame::make(Vec3(0, 0, 2), feed);
        CHECK(fr.plunge);
        CHECK(fr.n == Vec3(0, 0, 1));
        CHECK(glm::dot(fr.d, fr.n) == Approx(0).margin(1e-15));
        CHECK(glm::dot(fr.e, fr.n) == Approx(0).margin(1e-15));
        CHECK(glm::dot(fr.d, fr.e) == Approx(0).margin(1e-15));
    }
    CHECK_THROWS_AS(ToolFrame::make(Vec3(0.0), Vec3(1, 0, 0)), Error);
}

TEST_CASE("parse errors carry file, line, column and the offending text", "[geometry][errors]") {
    const ParseError e({"part.ngc", 12, 7}, "bad number", "1.2.3");
    CHECK(std::string(e.what()) == "part.ngc:12:7: error: bad number: '1.2.3'");
    CHECK(e.where().line == 12);
    CHECK(SourceLocation{"a.apt", 3, 0}.str() == "a.apt:3");
}

TEST_CASE("packed normals: within the stated angle of the unit vector, flags kept", "[geometry]") {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> gauss;
    double worst = 0.0;
    auto check = [&](const Vec3& v) {
        const Vec3 u = glm::normalize(v);
        const PackedNormal p = PackedNormal::pack(v);
        REQUIRE(p.present());
        REQUIRE_FALSE(p.sharp());
        const Vec3 d = p.unpack();
        REQUIRE(glm::length(d) == Approx(1.0).epsilon(1e-12));
        worst = std::max(worst, std::acos(std::clamp(glm::dot(u, d), -1.0, 1.0)));
    };
    for (int i = 0; i < 1000000; ++i) check(Vec3(gauss(rng), gauss(rng), gauss(rng)));
    // The octahedron's vertices and edge midpoints, where the fold meets itself.
    for (int a = 0; a < 3; ++a)
        for (double s : {1.0, -1.0}) {
            Vec3 v(0.0);
            v[a] = s;
            check(v);
            v[(a + 1) % 3] = -s;
            check(v);
        }
    INFO("worst angle " << worst);
    CHECK(worst <= PackedNormal::kMaxAngleError);
    // Axis directions come back exactly: the box faces' normals.
    CHECK(PackedNormal::pack(Vec3(0, 0, -1)).unpack() == Vec3(0, 0, -1));
    CHECK(PackedNormal::pack(Vec3(1, 0, 0)).unpack() == Vec3(1, 0, 0));
    // Sharp marks, flips, and "no normal".
    const PackedNormal s = PackedNormal::pack(Vec3(1, 2, 3), true);
    CHECK(s.sharp());
    CHECK(s.flipped().sharp());
    CHECK(glm::dot(s.flipped().unpack(), glm::normalize(Vec3(-1, -2, -3))) > 1.0 - 1e-7);
    CHECK_FALSE(s.withSharp(false).sharp());
    CHECK_FALSE(PackedNormal::pack(Vec3(0.0)).present());
    CHECK_FALSE(PackedNormal::pack(Vec3(std::nan(""), 0, 1)).present());
    CHECK(PackedNormal{}.unpack() == Vec3(0.0));
}
