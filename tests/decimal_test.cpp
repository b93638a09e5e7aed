// Decimal numbers as options, tool specs and memory sizes read them, and as messages compare them.
#include <catch2/catch.hpp>

#include <optional>
#include <string>

#include "dexelmill/decimal.h"

using namespace dexelmill;

TEST_CASE("decimal: a number written in decimal reads as the nearest double", "[decimal]") {
    const std::pair<const char*, double> cases[] = {
        {"6", 6.0},     {"-2.5", -2.5}, {"+3", 3.0},         {".5", 0.5},        {"7.", 7.0},
        {"1e3", 1000.0}, {"1.5E-2", 0.015}, {"-0", -0.0},    {" 4\t", 4.0},      {"1e-310", 1e-310},
    };
    for (const auto& [text, value] : cases) {
        INFO(text);
        const std::optional<double> v = parseDecimal(text);
        REQUIRE(v);
        CHECK(*v == value);
    }
}

TEST_CASE("decimal: hexadecimal, infinities, NaN and numbers beyond a double are not decimal numbers",
          "[decimal]") {
    // std::stod and strtod read the first four as 16, 6, infinity and NaN.
    for (const char* text : {"0x10", "0X6", "0x1p4", "inf", "-infinity", "nan", "NAN(1)", "1e400", "-1e400", "1e-400",
                             "", " ", ".", "e5", "1e", "1e+", "+-1", "1,5", "1.2.3", "6mm", "6 7"}) {
        INFO("'" << text << "'");
        CHECK_FALSE(parseDecimal(text));
    }
}

TEST_CASE("decimal: two values a message compares print with the digits that tell them apart", "[decimal]") {
    const auto [r, half] = decimalsApart(1.98438, 3.96875 / 2);
    CHECK(r == "1.98438");
    CHECK(half == "1.984375");
    const auto [far, reach] = decimalsApart(1000000001.0, 1e9);
    CHECK(far == "1000000001");
    CHECK(reach == "1000000000");
    // Six significant digits where they already differ, and where the two are equal.
    CHECK(decimalsApart(1.0, 2.0) == std::pair<std::string, std::string>{"1", "2"});
    CHECK(decimalsApart(1.0 / 3.0, 1.0 / 3.0) == std::pair<std::string, std::string>{"0.333333", "0.333333"});
}

TEST_CASE("decimal: a volume prints to a thousandth of a cubic millimetre, rounding noise as 0", "[decimal]") {
    // The excess of a part that matches its design, summed over many dexels: 1.7e-15 mm^3.
    CHECK(volumeText(1.7e-15) == "0.000 mm^3");
    CHECK(volumeText(-1.7e-15) == "0.000 mm^3");
    CHECK(volumeText(0.0) == "0.000 mm^3");
    CHECK(volumeText(-0.0) == "0.000 mm^3");
    CHECK(volumeText(12.3456) == "12.346 mm^3");
    CHECK(volumeText(0.0125) == "0.013 mm^3");
    CHECK(volumeText(-2.5) == "-2.500 mm^3");
    CHECK(volumeText(612345.0) == "612345 mm^3");
    CHECK(volumeText(1234.5678) == "1234.57 mm^3");
    CHECK(volumeText(80707312.4) == "80707312 mm^3");
    CHECK(volumeText(-1.5e30).find('e') == std::string::npos);
    CHECK(volumeText(INFINITY) == "inf mm^3");
}

TEST_CASE("decimal: a length prints with four significant digits to a nanometre, never with an exponent",
          "[decimal]") {
    CHECK(lengthText(0.125) == "0.125");
    CHECK(lengthText(5.0) == "5");
    CHECK(lengthText(0.0514545) == "0.05145");
    CHECK(lengthText(-1.5) == "-1.5");
    CHECK(lengthText(12345.6) == "12346");
    CHECK(lengthText(0.0001) == "0.0001");
    CHECK(lengthText(9.99999) == "10");
    // Rounding noise and what lies below a nanometre print as 0, whatever the sign.
    CHECK(lengthText(2.344e-13) == "0");
    CHECK(lengthText(-2.344e-13) == "0");
    CHECK(lengthText(-0.0) == "0");
    CHECK(lengthText(4e-7) == "0");
    CHECK(lengthText(6e-7) == "0.000001");
    for (const double mm : {1e-300, 1e-9, 1.5e30, -7.25e12, 3.0e-5})
        CHECK(lengthText(mm).find_first_of("eE") == std::string::npos);
    // Signed: a "+" only before a length that does not print as 0.
    CHECK(signedLengthText(0.05) == "+0.05");
    CHECK(signedLengthText(-0.01) == "-0.01");
    CHECK(signedLengthText(4e-7) == "0");
    CHECK(signedLengthText(0.0) == "0");
}

TEST_CASE("decimal: an area prints with six significant digits to a square micrometre, never with an exponent",
          "[decimal]") {
    CHECK(areaText(8397.98405) == "8397.98");
    CHECK(areaText(1000000.0) == "1000000");
    CHECK(areaText(4.123494) == "4.12349");
    CHECK(areaText(0.0) == "0");
    CHECK(areaText(1.2e-5) == "0.000012");
    CHECK(areaText(3e-8) == "0");
    CHECK(areaText(2.5e21).find_first_of("eE") == std::string::npos);
}
