// dexelmill's launcher: starts the tool (dexelmill-core, in the same folder) with glibc's malloc
// told to ask for transparent huge pages for its heap, where that helps.
//
// The level set's leaves (2 KiB each) and the dexels' tiles are small allocations from malloc's
// heap, whose memory the kernel gives a 4 KiB page, and one page fault, at a time; on virtual
// machines a fault is dear (about 12 us here). The hood's rebuild at 1 mm faults in 111,500 such
// pages (0.44 GB). glibc advises its heap for huge pages when its tunable glibc.malloc.hugetlb is
// 1 (memory/heap_tunable.h), but reads tunables only from the environment a process starts with.
// The tool cannot set it for itself cheaply: loading it takes 60 ms (OpenVDB's 69,000
// relocations), and starting again would pay that twice. This launcher links nothing but the C
// and C++ runtimes, so going through it costs about a millisecond.
//
// It sets the tunable only where the kernel gives huge pages on advice alone (mode "madvise";
// with "always" the heap has them already), where malloc is glibc's and reads it, and where
// GLIBC_TUNABLES does not name it already: a user's glibc.malloc.hugetlb=0 keeps it off.
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <unistd.h>

#include "memory/heap_tunable.h"
#include "memory/pages.h"

namespace {

/// The folder of this executable, with its trailing '/' ("" when unknown: then the tool is
/// looked for as argv[0] names this one).
std::string ownFolder(const char* argv0) {
    std::string path;
    char buffer[4096];
    const ssize_t n = readlink("/proc/self/exe", buffer, sizeof buffer - 1);
    if (n > 0) path.assign(buffer, std::size_t(n));
    else if (argv0) path = argv0;
    const std::size_t slash = path.rfind('/');
    return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

}  // namespace

int main(int, char** argv) {
    using namespace dexelmill::detail;
    const char* tunables = std::getenv("GLIBC_TUNABLES");
    if (hugePageMode() == "madvise" && mallocReadsHugeHeapTunable() && !tunableValue(tunables, kHugeHeapTunable)) {
        const std::string before = tunables ? tunables : "";
        const std::string after = (before.empty() ? "" : before + ":") + kHugeHeapTunable + "=1";
        setenv("GLIBC_TUNABLES", after.c_str(), 1);
    }
    const char* preload = std::getenv("LD_PRELOAD");
    if (preload && std::strstr(preload, "vgpreload"))
        std::fprintf(stderr, "dexelmill: valgrind does not follow into dexelmill-core by default: run that "
                             "executable itself, or give valgrind --trace-children=yes\n");
    const std::string core = ownFolder(argv[0]) + "dexelmill-core";
    execv(core.c_str(), argv);
    std::fprintf(stderr, "dexelmill: cannot start '%s': %s\n", core.c_str(), std::strerror(errno));
    return 1;
}
