#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

#include "dexelmill/geometry/roots.h"

using namespace dexelmill;

// Each function below changes sign exactly at a known root r: x - r is computed with its exact sign,
// and the factor it is multiplied by is positive, so the brackets can be checked against r itself.

TEST_CASE("newtonBracket: a bracket at most tol wide around the root, in few steps", "[geometry][roots]") {
    std::mt19937 rng(41);
    std::uniform_real_distribution<double> root(-50.0, 50.0), side(0.01, 20.0), curve(0.0, 3.0);
    for (int i = 0; i < 2000; ++i) {
        const double r = root(rng), lo = r - side(rng), hi = r + side(rng), c = curve(rng);
        const double sign = i % 2 ? 1.0 : -1.0;  // increasing and decreasing
        const auto value = [&](double x) { return sign * (x - r) * (1.0 + c * (x - r) * (x - r)); };
        int evals = 0;
        const auto f = [&](double x, double& fx, double& dfx) {
            ++evals;
            fx = value(x);
            dfx = sign * (1.0 + 3.0 * c * (x - r) * (x - r));
            return true;
        };
        const double tol = 1e-12;
        const auto [a, b] = newtonBracket(f, lo, hi, value(lo), value(hi), tol);
        INFO("root " << r << " bracket " << lo << " " << hi << " curve " << c);
        CHECK(a <= r);
        CHECK(r <= b);
        CHECK(b - a <= tol);
        // Bisection alone takes 34 to 45 steps on these brackets; these take at most 14.
        CHECK(evals <= 16);
    }
}

TEST_CASE("newtonBracket: Newton steps that leave the bracket are replaced by bisection",
          "[geometry][roots]") {
    // atan is flat far from its root: Newton's step from there overshoots the bracket.
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> root(-5.0, 5.0), side(1.0, 1000.0);
    for (int i = 0; i < 500; ++i) {
        const double r = root(rng), lo = r - side(rng), hi = r + side(rng);
        const auto f = [&](double x, double& fx, double& dfx) {
            fx = std::atan(x - r);
            dfx = 1.0 / (1.0 + (x - r) * (x - r));
            return true;
        };
        const auto [a, b] = newtonBracket(f, lo, hi, std::atan(lo - r), std::atan(hi - r), 1e-10);
        CHECK(a <= r);
        CHECK(r <= b);
        CHECK(b - a <= 1e-10);
    }
}

TEST_CASE("newtonBracket: stopping, a value without a sign, and tol 0", "[geometry][roots]") {
    const double r = 0.3;
    SECTION("f stops the search at the point it is called with") {
        double last = 0.0;
        int calls = 0;
        const auto f = [&](double x, double& fx, double& dfx) {
            last = x;
            fx = std::expm1(x - r), dfx = std::exp(x - r);
            return ++calls < 2;
        };
        const auto [a, b] = newtonBracket(f, 0.0, 1.0, std::expm1(-r), std::expm1(1.0 - r), 1e-12);
        CHECK(calls == 2);
        CHECK(a == last);
        CHECK(b == last);
    }
    SECTION("a NaN value bisects") {
        int nans = 0;
        const auto f = [&](double x, double& fx, double& dfx) {
            fx = x < 0.9 && x > 0.1 && nans < 3 ? (++nans, std::numeric_limits<double>::quiet_NaN())
                                                 : std::expm1(x - r);
            dfx = std::exp(x - r);
            return true;
        };
        const auto [a, b] = newtonBracket(f, 0.0, 1.0, std::expm1(-r), std::expm1(1.0 - r), 1e-12);
        CHECK(nans == 3);
        CHECK(a <= r);
        CHECK(r <= b);
        CHECK(b - a <= 1e-12);
    }
    SECTION("a zero at an end is the root, and f is called there last") {
        for (const bool atLower : {true, false}) {
            double last = -1.0;
            int calls = 0;
            const auto f = [&](double x, double& fx, double& dfx) {
                ++calls;
                last = x;
                fx = std::expm1(x - r), dfx = std::exp(x - r);
                return true;
            };
            // f = expm1(x - r) is 0 at r exactly: an end there, the other on either side.
            const double other = atLower ? 1.0 : -1.0;
            const double x0 = atLower ? r : other, x1 = atLower ? other : r;
            const auto [a, b] = newtonBracket(f, x0, x1, std::expm1(x0 - r), std::expm1(x1 - r), 0.0);
            CHECK(a == r);
            CHECK(b == r);
            CHECK(last == r);
            CHECK(calls == 1);
        }
    }
    SECTION("a root between two doubles: the bracket closes round it") {
        // x^2 - 2 is 0 at no double, so no step ends the search on an exact zero.
        int calls = 0;
        const auto f = [&](double x, double& fx, double& dfx) {
            ++calls;
            fx = x * x - 2.0, dfx = 2.0 * x;
            return true;
        };
        const auto [a, b] = newtonBracket(f, 0.0, 2.0, -2.0, 2.0, 1e-12);
        CHECK(static_cast<long double>(a) * a <= 2.0L);
        CHECK(static_cast<long double>(b) * b >= 2.0L);
        CHECK(b - a <= 1e-12);
        CHECK(calls <= 12);
    }
    SECTION("tol 0: the search runs until f stops it") {
        int calls = 0;
        double last = 0.0;
        const auto f = [&](double x, double& fx, double& dfx) {
            ++calls;
            last = x;
            fx = std::expm1(x - r), dfx = std::exp(x - r);
            return std::abs(fx) > 1e-14;
        };
        newtonBracket(f, -2.0, 3.0, std::expm1(-2.0 - r), std::expm1(3.0 - r), 0.0);
        CHECK(std::abs(last - r) <= 1e-14);
        CHECK(calls <= 12);
    }
}

TEST_CASE("newtonBracket: steps that near the root from one side are lengthened across it",
          "[geometry][roots]") {
    // x^2 - a is convex and increasing on [1, a]: after the first Newton step, every step lands on
    // the root's right and approaches it from there, so the bracket's left end stays where the
    // secant put it. A step shorter than tol / 2 is lengthened to tol / 2 and crosses the root,
    // which closes the bracket at once: at most 8 evaluations on these brackets at tols of 1e-3
    // and 1e-6. Unlengthened, the steps go on until rounding stops them, up to 21 and 31. The
    // value is exactly rounded (fma), so its sign is exact and the bracket can be checked against
    // the root's rounding.
    std::mt19937 rng(45);
    std::uniform_real_distribution<double> square(1.5, 100.0);
    for (const double tol : {1e-3, 1e-6}) {
        for (int i = 0; i < 1000; ++i) {
            const double a = square(rng);
            int evals = 0;
            const auto f = [&](double x, double& fx, double& dfx) {
                ++evals;
                fx = std::fma(x, x, -a), dfx = 2.0 * x;
                return true;
            };
            const auto [lo, hi] = newtonBracket(f, 1.0, a, 1.0 - a, std::fma(a, a, -a), tol);
            INFO("a = " << a << ", tol " << tol << ", bracket [" << lo << ", " << hi << "]");
            CHECK(lo <= std::sqrt(a));
            CHECK(std::sqrt(a) <= hi);
            CHECK(hi - lo <= tol);
            CHECK(evals <= 8);
        }
    }
}
