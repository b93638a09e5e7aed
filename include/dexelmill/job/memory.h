/// @file memory.h
/// @brief The process's memory and threads as the system reports them; how much memory a job may
/// use, and how much it will need: checked before the work that
/// would need it, so that a job too big for the machine stops at once with the figures, never with
/// an allocator's message.
#pragma once

#include <cstddef>
#include <string>

#include "dexelmill/stock/lattice.h"
#include "dexelmill/stock/tridexel.h"

namespace dexelmill {

/// @brief The memory this process may use, and what sets it.
struct MemoryBudget {
    std::size_t bytes = 0;
    /// "--max-memory", "the address-space limit (ulimit -v)", "the cgroup's memory.max" or
    /// "the memory available (MemAvailable)".
    std::string source;
    /// Whether the budget bounds the address space (ulimit -v), which counts every mapping the
    /// process holds (thread stacks, allocator arenas, libraries), not only the memory in use.
    bool addressSpace = false;
    /// Whether the system enforces the budget (ulimit -v, the cgroup), so that --max-memory cannot
    /// raise it.
    bool enforced = false;
    /// A warning for the user, empty when none: a `maxBytes` the system does not give.
    std::string note;
};

/// @brief What a message that a job does not fit `budget` adds about --max-memory: ", or set
/// --max-memory", ", or a larger --max-memory", or nothing where the system enforces the budget.
std::string moreMemoryAdvice(const MemoryBudget& budget);

/// @brief The budget: the least of the address-space limit, the cgroup's limit and the memory
/// available now plus what the process already holds; or `maxBytes` when it is not 0. A
/// `maxBytes` beyond one of the two limits, which the system enforces, is cut to it, and one
/// beyond the memory available (which may yet be freed) is kept; either way `note` says so.
MemoryBudget memoryBudget(std::size_t maxBytes = 0);

/// @brief The resident memory of this process now (bytes; 0 when the system does not say).
std::size_t residentBytes();

/// @brief What the budget counts of this process now (bytes): its address space (VmSize) where the
/// budget is the address-space limit, else its resident memory.
std::size_t bytesInUse(const MemoryBudget& budget);

/// @brief Peak resident memory of this process so far (MiB), or since resetPeakMemory.
double peakMemoryMb();

/// @brief The threads of this process now (0 when the system does not say).
std::size_t processThreadCount();

/// @brief The most threads this process can run at once: its cores within its CPU affinity (TBB's
/// default concurrency), and no more than its cgroup's CPU quota allows, rounded up.
int runnableThreads();

/// @brief The size of a job's task arena for a requested thread count: every runnable thread for
/// 0, else the request up to runnableThreads(). An arena larger than that runs no more threads,
/// and the stages size their work by the arena (a part per thread, a batch of buffers per
/// thread), so a request of 100,000 threads would only multiply their work and their memory.
/// Callers that take the count from a user say when it is cut (SimulateReport's warnings).
int arenaThreads(int requested);

/// @brief What to tell a user whose --threads `requested` arenaThreads cuts: the request, the
/// machine's limit and the count used. Empty when nothing is cut.
std::string threadsCutNote(int requested);

/// @brief Resident memory of this process now (MiB).
double currentMemoryMb();

/// @brief Starts peakMemoryMb afresh from the current resident size (Linux 4.0 and later, through
/// /proc/self/clear_refs), after handing freed heap memory back to the system, so that one stage's
/// peak can be measured on its own: its growth over currentMemoryMb() taken just after.
/// @return false when the system does not allow it (peakMemoryMb then keeps the process's peak).
bool resetPeakMemory();


/// @brief Whether glibc's malloc was told, in the environment this process started with, to ask the
/// kernel for transparent huge pages for its heap (the tunable glibc.malloc.hugetlb set to 1 or 2
/// in GLIBC_TUNABLES), as the tool's launcher does where that helps (src/launch).
bool heapOnHugePages();

/// @brief Reads a size such as "4G", "512M", "1.5GiB" or "800000000": a decimal number
/// (parseDecimal) and a unit (bytes; K, M, G and T are powers of 1024). @throw Error for anything
/// else.
std::size_t parseMemorySize(const std::string& text);

/// @brief "1.23 GiB", "456 MiB".
std::string formatBytes(double bytes);

/// @brief The most moves whose list fits in what the budget leaves free, and never more than
/// `limit`: a third of it, since a list of c moves that grows copies them into room for 2 c.
std::size_t movesThatFit(const MemoryBudget& budget, std::size_t limit);

/// @brief Memory the rebuild and the mesh take per surface crossing of a lattice edge: the level
/// set's narrow band, the dexel mesher's blocks and the mesh (four triangles per crossing) with
/// its check. Measured as the peak less the stock and the process before the rebuild on bear,
/// heart and scorpion (0.2 to 1.2 million crossings): 228 to 240 bytes.
constexpr double kSurfaceBytesPerCrossing = 256.0;

/// @brief Bytes of a fresh stock on `lattice` with the families kept: per dexel its offset,
/// count and one segment, per tile its bookkeeping.
double stockBytes(const Lattice& lattice, FamilySet families);

/// @brief The lattice edges crossing the surface of the box the lattice covers: the fewest
/// crossings any part cut from it can have, counted on the faces, for the families' directions
/// (a missing family's crossings are interpolated, and meshed all the same).
double boxCrossings(const Lattice& lattice);

/// @brief The crossings of a cut stock: two per segment, scaled to all three directions when
/// families are missing.
double stockCrossings(const TriDexelStock& stock);

/// @brief The finest spacing (rounded up to two significant digits) at which `need` bytes,
/// measured at spacing h and growing as h^-2, fall within `room` bytes.
double spacingThatFits(double h, double need, double room);

}  // namespace dexelmill
