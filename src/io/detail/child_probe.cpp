#include "child_probe.h"

#include <cerrno>
#include <csignal>

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace dexelmill::detail {

ChildEnd runInChild(const std::function<void()>& work) {
    const pid_t pid = fork();
    if (pid < 0) return {};
    if (pid == 0) {
        // The child: silent (an allocator's abort message is no message for the user), no core
        // file, and _exit, so that no handler the parent registered runs twice.
        const int null = open("/dev/null", O_WRONLY);
        if (null >= 0) {
            dup2(null, STDOUT_FILENO);
            dup2(null, STDERR_FILENO);
        }
        const rlimit noCore{0, 0};
        setrlimit(RLIMIT_CORE, &noCore);
        // The parent's handlers of a crash (a test framework's, which allocates to report it)
        // would run where the crash left the heap locked, and hang: a crash ends the child.
        for (const int crash : {SIGABRT, SIGSEGV, SIGBUS, SIGILL, SIGFPE}) std::signal(crash, SIG_DFL);
        try {
            work();
        } catch (...) {
            _exit(0);
        }
        _exit(0);
    }
    int status = 0;
    pid_t waited = 0;
    do waited = waitpid(pid, &status, 0);
    while (waited < 0 && errno == EINTR);
    if (waited != pid) return {};
    ChildEnd end;
    end.ran = true;
    end.crashed = !(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    end.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    return end;
}

}  // namespace dexelmill::detail
