#include <catch2/catch.hpp>

#include <csignal>

#include "io/detail/child_probe.h"

using dexelmill::detail::ChildEnd;
using dexelmill::detail::runProcess;

TEST_CASE("a process that aborts is reported crashed, and the caller goes on", "[io][errors]") {
    const ChildEnd aborted = runProcess("/bin/sh", {"-c", "echo this line goes to /dev/null >&2; kill -ABRT $$"});
    REQUIRE(aborted.ran);
    CHECK(aborted.crashed);
    CHECK(aborted.signal == SIGABRT);
    // A signal the caller ignores is at its default in the process, so it still ends it.
    const auto old = std::signal(SIGTERM, SIG_IGN);
    const ChildEnd terminated = runProcess("/bin/sh", {"-c", "kill -TERM $$; exit 0"});
    std::signal(SIGTERM, old);
    REQUIRE(terminated.ran);
    CHECK(terminated.signal == SIGTERM);
}

TEST_CASE("a process that exits 0 is not reported crashed, and one that exits otherwise is", "[io][errors]") {
    const ChildEnd returned = runProcess("/bin/sh", {"-c", "exit 0"});
    REQUIRE(returned.ran);
    CHECK_FALSE(returned.crashed);
    CHECK(returned.signal == 0);
    // A non-zero exit (a sanitizer's report ends so) counts as a crash.
    const ChildEnd exited = runProcess("/bin/sh", {"-c", "exit 3"});
    REQUIRE(exited.ran);
    CHECK(exited.crashed);
    CHECK(exited.signal == 0);
    // A program that cannot start tells nothing.
    CHECK_FALSE(runProcess("/nonexistent/program", {}).ran);
}
