#include "dexelmill/job/memory.h"

#include <malloc.h>
#include <sys/resource.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>

#include <tbb/info.h>

#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/path/toolpath.h"
#include "memory/heap_tunable.h"

namespace dexelmill {

namespace {

/// The number on a "Key:" line of a /proc file (0 when unavailable).
double procNumber(const char* file, const char* key) {
    std::ifstream in(file);
    std::string word;
    while (in >> word) {
        if (word == key) {
            double value = 0;
            in >> value;
            return value;
        }
        in.ignore(4096, '\n');
    }
    return 0.0;
}

/// The cgroup's memory limit (v2 memory.max, else v1 memory.limit_in_bytes); 0 for none.
std::size_t cgroupLimit() {
    for (const char* f : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
        std::ifstream in(f);
        std::string text;
        if (!(in >> text) || text == "max") continue;
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        // v1 reports "no limit" as a huge page-rounded number.
        if (end != text.c_str() && v > 0 && v < 1e18) return std::size_t(v);
    }
    return 0;
}

/// The CPUs the cgroup's quota allows (v2 cpu.max "QUOTA PERIOD", else v1 cpu.cfs_quota_us and
/// cpu.cfs_period_us), rounded up; 0 for no quota. TBB 2021's default concurrency does not read it.
int cgroupCpus() {
    double quota = 0.0, period = 0.0;
    {
        std::ifstream in("/sys/fs/cgroup/cpu.max");
        std::string q;
        if (in >> q >> period && q != "max") quota = std::strtod(q.c_str(), nullptr);
    }
    if (!(quota > 0.0 && period > 0.0)) {
        std::ifstream q("/sys/fs/cgroup/cpu/cpu.cfs_quota_us"), p("/sys/fs/cgroup/cpu/cpu.cfs_period_us");
        if (!(q >> quota && p >> period)) return 0;  // v1 says -1 for no quota
    }
    if (!(quota > 0.0 && period > 0.0)) return 0;
    return int(std::max(1.0, std::ceil(quota / period)));
}

}  // namespace

double peakMemoryMb() { return procNumber("/proc/self/status", "VmHWM:") / 1024.0; }

double currentMemoryMb() { return double(residentBytes()) / (1024.0 * 1024.0); }

std::size_t processThreadCount() { return std::size_t(procNumber("/proc/self/status", "Threads:")); }

int runnableThreads() {
    static const int runnable = [] {
        const int cores = std::max(1, tbb::info::default_concurrency());  // within the CPU affinity
        const int quota = cgroupCpus();
        return quota > 0 ? std::min(cores, quota) : cores;
    }();
    return runnable;
}

int arenaThreads(int requested) {
    return requested > 0 ? std::min(requested, runnableThreads()) : runnableThreads();
}

std::string threadsCutNote(int requested) {
    const int runnable = runnableThreads();
    if (requested <= runnable) return {};
    return "--threads " + std::to_string(requested) + ": this machine runs at most " + std::to_string(runnable) +
           " threads at once (its cores, within the process's CPU affinity and quota); the job uses " +
           std::to_string(runnable);
}

bool resetPeakMemory() {
    malloc_trim(0);  // hand freed heap back first, so that the next peak is the next stage's own
    std::ofstream out("/proc/self/clear_refs");
    out << "5";  // 5: reset the peak resident set size (proc(5))
    out.flush();
    return bool(out);
}

bool heapOnHugePages() {
    return detail::mallocReadsHugeHeapTunable() && detail::asksHugeHeap(std::getenv("GLIBC_TUNABLES"));
}

std::size_t residentBytes() { return std::size_t(procNumber("/proc/self/status", "VmRSS:") * 1024.0); }

std::size_t bytesInUse(const MemoryBudget& budget) {
    if (!budget.addressSpace) return residentBytes();
    return std::size_t(procNumber("/proc/self/status", "VmSize:") * 1024.0);
}

MemoryBudget memoryBudget(std::size_t maxBytes) {
    MemoryBudget b{std::numeric_limits<std::size_t>::max(), "no limit the system states", false, false, {}};
    auto take = [&](std::size_t bytes, const char* source, bool addressSpace = false) {
        if (bytes > 0 && bytes < b.bytes) b = {bytes, source, addressSpace, false, {}};
    };
    rlimit as{};
    if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY)
        take(std::size_t(as.rlim_cur), "the address-space limit (ulimit -v)", true);
    take(cgroupLimit(), "the cgroup's memory.max");
    b.enforced = b.bytes != std::numeric_limits<std::size_t>::max();
    const MemoryBudget enforced = b;
    const double available = procNumber("/proc/meminfo", "MemAvailable:") * 1024.0;
    if (available > 0) take(std::size_t(available) + residentBytes(), "the memory available (MemAvailable)");
    if (maxBytes == 0) return b;
    const std::string asked = "--max-memory " + formatBytes(double(maxBytes));
    if (maxBytes > enforced.bytes) {
        MemoryBudget cut = enforced;
        cut.source += ", less than " + asked;
        cut.note = asked + " is more than " + enforced.source + " allows: the job keeps to " +
                   formatBytes(double(enforced.bytes));
        return cut;
    }
    MemoryBudget given{maxBytes, "--max-memory", false, false, {}};
    if (maxBytes > b.bytes)
        given.note = asked + " is more than " + b.source + ", " + formatBytes(double(b.bytes)) +
                     " now: the job may run out of memory or swap";
    return given;
}

std::string moreMemoryAdvice(const MemoryBudget& budget) {
    if (budget.enforced) return "";
    return budget.source == "--max-memory" ? ", or a larger --max-memory" : ", or set --max-memory";
}

std::size_t parseMemorySize(const std::string& text) {
    // The unit is the letters that end the text; the number before it is decimal.
    std::size_t split = text.size();
    while (split > 0 && std::isalpha(static_cast<unsigned char>(text[split - 1]))) --split;
    const std::optional<double> number = parseDecimal(std::string_view(text).substr(0, split));
    std::string unit = text.substr(split);
    for (char& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
    const double v = number.value_or(0.0);
    double scale = 0.0;
    if (unit.empty() || unit == "B") scale = 1.0;
    else if (unit == "K" || unit == "KB" || unit == "KIB") scale = 1024.0;
    else if (unit == "M" || unit == "MB" || unit == "MIB") scale = 1024.0 * 1024.0;
    else if (unit == "G" || unit == "GB" || unit == "GIB") scale = 1024.0 * 1024.0 * 1024.0;
    else if (unit == "T" || unit == "TB" || unit == "TIB") scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
    if (!number || scale == 0.0 || !(v > 0) || v * scale > 1e18)
        throw Error("'" + text + "' is not a memory size (for example 4G, 512M or 800000000)");
    return std::size_t(v * scale);
}

std::string formatBytes(double bytes) {
    char buf[48];
    if (bytes >= 1024.0 * 1024.0 * 1024.0) std::snprintf(buf, sizeof buf, "%.3g GiB", bytes / (1024.0 * 1024.0 * 1024.0));
    else std::snprintf(buf, sizeof buf, "%.3g MiB", bytes / (1024.0 * 1024.0));
    return buf;
}

std::size_t movesThatFit(const MemoryBudget& budget, std::size_t limit) {
    const double free = double(budget.bytes) - double(bytesInUse(budget));
    return std::size_t(std::min(double(limit), std::max(0.0, free / (3.0 * sizeof(Move)))));
}

double stockBytes(const Lattice& lattice, FamilySet families) {
    // A tile of 16 x 16 dexels: 257 offsets, 256 counts and, fresh, one segment per dexel.
    constexpr double kTileDexels = 256.0;
    const double perDexel = (257.0 * sizeof(std::uint32_t) + kTileDexels * sizeof(std::uint16_t) +
                             kTileDexels * sizeof(Segment) + sizeof(DexelTile)) / kTileDexels;
    const double nx = lattice.n[0], ny = lattice.n[1], nz = lattice.n[2];
    double dexels = 0.0;
    if (families.has(Axis::X)) dexels += ny * nz;
    if (families.has(Axis::Y)) dexels += nz * nx;
    if (families.has(Axis::Z)) dexels += nx * ny;
    return dexels * perDexel;
}

double boxCrossings(const Lattice& lattice) {
    const double nx = lattice.n[0], ny = lattice.n[1], nz = lattice.n[2];
    return 2.0 * (ny * nz + nz * nx + nx * ny);
}

double stockCrossings(const TriDexelStock& stock) {
    const int kept = stock.families().count();
    if (kept == 0) return 0.0;
    return 2.0 * double(stock.segmentCount()) * 3.0 / kept;
}

double spacingThatFits(double h, double need, double room) {
    if (!(room > 0)) return std::numeric_limits<double>::infinity();
    const double raw = h * std::sqrt(std::max(1.0, need / room));
    const double decade = std::pow(10.0, std::floor(std::log10(raw)) - 1.0);
    return std::ceil(raw / decade * (1.0 - 1e-12)) * decade;
}

}  // namespace dexelmill
