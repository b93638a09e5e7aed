#include <catch2/catch.hpp>

#include <cmath>

#include "dexelmill/error.h"
#include "dexelmill/tool/spec.h"

using namespace dexelmill;
using Catch::Matchers::Contains;

namespace {
std::string errorOf(const std::string& spec) {
    try {
        parseToolSpec(spec);
    } catch (const Error& e) {
        return e.what();
    }
    return "<no error>";
}
}  // namespace

TEST_CASE("tool specs build the tools they name", "[tool]") {
    const Tool ball = parseToolSpec("ball:d=6");
    CHECK(ball.radiusAt(0) == 0);
    CHECK(ball.radiusAt(3) == Approx(3));
    const Tool flat = parseToolSpec("flat:d=10,length=25,total=60");
    CHECK(flat.radiusAt(0) == 5);
    CHECK(flat.cuttingLength() == 25);
    CHECK(flat.totalLength() == 60);
    const Tool bull = parseToolSpec("bull:d=10,r=2");
    CHECK(bull.radiusAt(0) == Approx(3));
    CHECK(bull.radiusAt(2) == Approx(5));
    const Tool taper = parseToolSpec("taper:d=2,angle=15,length=10");
    CHECK(taper.radiusAt(10) == Approx(1 + 10 * std::tan(15 * M_PI / 180)));
    const Tool vbit = parseToolSpec("vbit:d=6,angle=30");
    CHECK(vbit.radiusAt(0) == 0);
    CHECK(vbit.radiusAt(1) == Approx(std::tan(30 * M_PI / 180)));
    CHECK(parseToolSpec("chamfer:d=12,angle=45,tip=3").radiusAt(0) == Approx(1.5));
    CHECK(parseToolSpec("drill:d=6").radiusAt(1) == Approx(std::tan(59 * M_PI / 180)));
    CHECK(parseToolSpec("taperball:d=3,angle=5").radiusAt(0) == 0);
    const Tool apt = parseToolSpec("apt:12,0,6,4.5,45,0,73");
    CHECK(apt.radiusAt(0) == Approx(1.5));
    CHECK(apt.totalLength() == 73);
}

TEST_CASE("bad tool specs say what is wrong", "[tool][errors]") {
    CHECK_THAT(errorOf("ball"), Contains("KIND:PARAMETERS"));
    CHECK_THAT(errorOf("ball:d=six"), Contains("'six' is not a number"));
    CHECK_THAT(errorOf("ball:r=3"), Contains("missing d="));
    CHECK_THAT(errorOf("ball:d=6,q=1"), Contains("unknown parameter 'q'"));
    CHECK_THAT(errorOf("ball:d=6,d=7"), Contains("'d' is given twice"));
    CHECK_THAT(errorOf("bull:d=10,r=6"), Contains("corner radius r = 6"));
    CHECK_THAT(errorOf("saw:d=100"), Contains("unknown kind 'saw'"));
    CHECK_THAT(errorOf("apt:10,0,5"), Contains("7 values"));
    CHECK_THAT(errorOf("apt:100.1,2,48,2,0,0,50"), Contains("d = 100.1 is not the diameter its corner makes"));
    CHECK_THAT(errorOf("flat:6"), Contains("name=value"));
    CHECK_THAT(errorOf("ball:d=0"), Contains("diameter d must be positive"));
    // A length written as 0 is no default: a tool without flutes or body.
    CHECK_THAT(errorOf("flat:d=4,length=0"), Contains("flat:d=4,length=0': length must be positive, got 0"));
    CHECK_THAT(errorOf("flat:d=4,total=0"), Contains("total must be positive, got 0"));
    CHECK_THAT(errorOf("flat:d=4,length=-2"), Contains("length must be positive, got -2"));
    // Only total given: no complaint about a cutting length the spec never set.
    CHECK(parseToolSpec("ball:d=6,total=15").cuttingLength() == 15);
    CHECK_THAT(errorOf("drill:d=6,total=1"), Contains("total length 1 mm does not clear the 1.80258 mm point"));
}

TEST_CASE("tool spec numbers are decimal, as every option's are", "[tool][errors]") {
    // std::stod reads the first three as 6, infinity and NaN.
    for (const char* number : {"0x6", "inf", "nan", "1e400", "6mm"}) {
        INFO(number);
        CHECK_THAT(errorOf(std::string("flat:d=") + number), Contains(std::string("'") + number + "' is not a number"));
    }
    CHECK_THAT(errorOf("flat:d=6,total=0X40"), Contains("'0X40' is not a number"));
}

TEST_CASE("a tool spec larger than a tool may be is refused, naming the parameter", "[tool][errors]") {
    CHECK_THAT(errorOf("flat:d=1e155"), Contains("diameter d = 1e+155 mm is beyond the 10000 mm a tool may measure"));
    CHECK_THAT(errorOf("ball:d=1e155"), Contains("diameter d = 1e+155 mm is beyond the 10000 mm"));
    CHECK_THAT(errorOf("flat:d=6,total=1e300"), Contains("total length = 1e+300 mm is beyond the 10000 mm"));
    CHECK_THAT(errorOf("apt:10,0,5,0,0,0,2e4"), Contains("h = 20000 mm is beyond the 10000 mm"));
}

TEST_CASE("a holder sits above the stick-out and needs both its sizes", "[tool]") {
    const Tool t = parseToolSpec("flat:d=10,length=15,total=20,holder=32,holderlength=40");
    CHECK(t.cuttingLength() == 15);
    CHECK(t.totalLength() == 60);
    CHECK(t.radiusAt(19.5) == 5);
    CHECK(t.radiusAt(20.5) == 16);
    CHECK(t.radiusAt(59.5) == 16);
    CHECK(t.hasHolder());
    CHECK_FALSE(parseToolSpec("flat:d=10,length=15,total=20").hasHolder());
    // The shank region holds the holder; a region below it does not.
    CHECK(t.region(15, 60).hasHolder());
    CHECK_FALSE(t.region(15, 20).hasHolder());
    CHECK_THAT(t.description(), Contains("holder D32 L40"));
    // A holder as wide as the shank lengthens it.
    CHECK(parseToolSpec("ball:d=6,total=20,holder=6,holderlength=5").radiusAt(24) == 3);

    CHECK_THAT(errorOf("flat:d=10,holder=32"), Contains("both holder=D and holderlength=L"));
    CHECK_THAT(errorOf("flat:d=10,holderlength=32"), Contains("both holder=D and holderlength=L"));
    CHECK_THAT(errorOf("flat:d=10,holder=8,holderlength=30"),
               Contains("diameter 8 mm is narrower than the tool it holds, 10 mm at its top"));
    // A taper's shank keeps its top radius: 1 + 10 tan 15 deg = 3.68 mm, 7.36 across.
    CHECK_THAT(errorOf("taper:d=2,angle=15,length=10,holder=7,holderlength=30"), Contains("7.35898 mm at its top"));
    CHECK_THAT(errorOf("flat:d=10,holder=0,holderlength=30"), Contains("diameter must be positive, got 0"));
    CHECK_THAT(errorOf("flat:d=10,holder=30,holderlength=-1"), Contains("length must be positive, got -1"));
    CHECK_THAT(errorOf("flat:d=10,holder=30,holderlength=9990"), Contains("10000"));
}
