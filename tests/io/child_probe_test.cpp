#include <catch2/catch.hpp>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include <unistd.h>

#include "io/detail/child_probe.h"

using dexelmill::detail::ChildEnd;
using dexelmill::detail::runInChild;

TEST_CASE("a child that aborts is reported crashed, and the parent goes on", "[io][errors]") {
    int touched = 0;
    const ChildEnd aborted = runInChild([&] {
        touched = 1;  // the child's copy: the parent's stays 0
        std::fputs("this line goes to /dev/null\n", stderr);
        std::abort();
    });
    REQUIRE(aborted.ran);
    CHECK(aborted.crashed);
    CHECK(aborted.signal == SIGABRT);
    CHECK(touched == 0);
}

TEST_CASE("a child that returns or throws is not reported crashed", "[io][errors]") {
    const ChildEnd returned = runInChild([] {});
    REQUIRE(returned.ran);
    CHECK_FALSE(returned.crashed);
    CHECK(returned.signal == 0);
    // An exception is the caller's to meet with its own message, when it runs the work itself.
    const ChildEnd threw = runInChild([] { throw std::runtime_error("damaged"); });
    REQUIRE(threw.ran);
    CHECK_FALSE(threw.crashed);
    // A non-zero exit (a sanitizer's report ends so) counts as a crash.
    const ChildEnd exited = runInChild([] { ::_exit(3); });
    REQUIRE(exited.ran);
    CHECK(exited.crashed);
    CHECK(exited.signal == 0);
}
