#include "dexelmill/study/study.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <random>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "dexelmill/compare/deviation.h"
#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/io/file_name.h"
#include "dexelmill/io/mesh_io.h"
#include "dexelmill/job/memory.h"
#include "dexelmill/study/oracle.h"

namespace dexelmill {

namespace {

/// Search range for the exact surface along a point's normal (and, where that fails, along the
/// axes), in spacings; a point farther than this from the exact surface is reported at this
/// distance.
constexpr double kSearchSpacings = 4.0;
/// Bisection steps along the normal: the distance is then known to 2^-40 of the range.
constexpr int kBisections = 40;
/// A distance along the normal longer than this fraction of the search range (a quarter of a
/// spacing) is checked along the six axis directions as well.
constexpr double kAxisCheckFraction = 1.0 / 16.0;

/// Vertex normals: the sum of the adjacent triangles' area vectors, normalised.
std::vector<Vec3> vertexNormals(const Mesh& mesh) {
    std::vector<Vec3> n(mesh.vertices.size(), Vec3(0.0));
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Vec3 a = mesh.areaVector(t);
        for (std::uint32_t v : mesh.triangles[t]) n[v] += a;
    }
    for (Vec3& v : n) {
        const double l = glm::length(v);
        if (l > 0) v /= l;
    }
    return n;
}

/// Signed distance from the exact surface to p along the unit direction n (+ when p is outside
/// the exact part, i.e. the model holds extra material there), found by bisection on the
/// oracle's membership; none when membership does not change within `range`.
std::optional<double> signedDistanceAlong(const MachinedSolidOracle& oracle, const Vec3& p, const Vec3& n,
                                          double range) {
    const bool in = oracle.inside(p);
    // Walk outwards (p inside) or inwards (p outside) until membership flips.
    const Vec3 dir = in ? n : -n;
    double lo = 0, hi = 0;
    bool found = false;
    for (double step = range / 16; hi < range;) {
        lo = hi;
        hi = std::min(range, hi + step);
        if (oracle.inside(p + hi * dir) != in) {
            found = true;
            break;
        }
    }
    if (!found) return std::nullopt;
    for (int i = 0; i < kBisections; ++i) {
        const double mid = 0.5 * (lo + hi);
        (oracle.inside(p + mid * dir) == in ? lo : hi) = mid;
    }
    const double d = 0.5 * (lo + hi);
    return in ? -d : d;
}

/// The signed distance of p to the exact surface, from above: the distance along any direction to
/// where membership flips is a surface point's, so it bounds the distance to the nearest. Along
/// the normal n first. Where that is long, or finds nothing, the shortest of it and the distances
/// along the six axis directions is taken: a normal may leave the stock box before it meets the
/// part (a point just outside the part on a rim where a cut meets a face, its normal leaning out
/// of the face), or run along a floor past a wall that is nearer (a floor point just beyond a
/// slot's round end, whose normal meets the stock's top a depth away). Clamped to +-range where
/// none finds the surface.
double signedDistance(const MachinedSolidOracle& oracle, const Vec3& p, const Vec3& n, double range) {
    const std::optional<double> along = signedDistanceAlong(oracle, p, n, range);
    if (along && std::abs(*along) <= kAxisCheckFraction * range) return *along;
    std::optional<double> shortest = along;
    for (int a = 0; a < 3; ++a) {
        for (const double sign : {-1.0, 1.0}) {
            Vec3 axis(0.0);
            axis[a] = sign;
            const std::optional<double> d = signedDistanceAlong(oracle, p, axis, range);
            if (d && (!shortest || std::abs(*d) < std::abs(*shortest))) shortest = d;
        }
    }
    if (shortest) return *shortest;
    return oracle.inside(p) ? -range : range;
}

/// Distance from a point inside `box` to the nearest of its faces.
double faceDistance(const Box& box, const Vec3& p) {
    return std::min({p.x - box.lo.x, box.hi.x - p.x, p.y - box.lo.y, box.hi.y - p.y, p.z - box.lo.z, box.hi.z - p.z});
}

/// Statistics of signed deviations: largest and 95th percentile of the magnitudes, RMS, mean.
struct DeviationStats {
    double max = 0.0, rms = 0.0, p95 = 0.0, mean = 0.0;
};

DeviationStats deviationStats(const std::vector<double>& dev) {
    DeviationStats st;
    if (dev.empty()) return st;
    std::vector<double> mag(dev.size());
    double sum2 = 0, sum = 0;
    for (std::size_t i = 0; i < dev.size(); ++i) {
        mag[i] = std::abs(dev[i]);
        sum2 += dev[i] * dev[i];
        sum += dev[i];
    }
    st.max = *std::max_element(mag.begin(), mag.end());
    st.rms = std::sqrt(sum2 / double(dev.size()));
    st.mean = sum / double(dev.size());
    const std::size_t k = mag.size() * 95 / 100;
    std::nth_element(mag.begin(), mag.begin() + std::ptrdiff_t(k), mag.end());
    st.p95 = mag[k];
    return st;
}

/// A point on the mesh and its triangle's unit normal.
struct SurfacePoint {
    Vec3 p, n;
};

/// A sample point's findings: in the exact part and not the model (lost) or the reverse
/// (invented), and whether more than one spacing from the model's surface (far).
struct SampleCounts {
    std::size_t lost = 0, invented = 0, lostFar = 0, inventedFar = 0;
};

/// Memory a run holds per surface point measured: the point and its normal, its deviation, and
/// the copies the statistics take of it (the inner points' and the magnitudes).
constexpr double kBytesPerSurfacePoint = sizeof(SurfacePoint) + 3 * sizeof(double);
/// Memory a run holds per sample point: the point and its counts.
constexpr double kBytesPerSamplePoint = sizeof(Vec3) + sizeof(SampleCounts);

/// Fails before any run where the points measured per run would not fit in what the job's memory
/// budget leaves free now; each run's own stock and surface are checked by the job.
void checkPointsFit(const StudyOptions& o) {
    if (o.surfacePoints == 0 || o.samplePoints == 0)
        throw Error("a study measures at least one point on the mesh (--surface-points) and one in the stock "
                    "(--samples) per run");
    const MemoryBudget budget = memoryBudget(o.job.maxMemoryBytes);
    const double need =
        double(o.surfacePoints) * kBytesPerSurfacePoint + double(o.samplePoints) * kBytesPerSamplePoint;
    const double base = double(bytesInUse(budget));
    if (base + need <= double(budget.bytes)) return;
    char text[512];
    std::snprintf(text, sizeof text,
                  "%zu points on the mesh (--surface-points) and %zu in the stock (--samples) need about %s per run "
                  "on top of the %s in use, more than the %s this job may use (%s); measure fewer points, or set "
                  "--max-memory",
                  o.surfacePoints, o.samplePoints, formatBytes(need).c_str(), formatBytes(base).c_str(),
                  formatBytes(double(budget.bytes)).c_str(), budget.source.c_str());
    throw Error(text);
}

/// `count` points uniform over the triangles' area (fixed seed), each with its triangle's normal;
/// triangles without area are never picked.
std::vector<SurfacePoint> surfacePoints(const Mesh& mesh, std::size_t count) {
    std::vector<double> cumulative(mesh.triangles.size());
    double total = 0.0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        total += 0.5 * glm::length(mesh.areaVector(t));
        cumulative[t] = total;
    }
    std::vector<SurfacePoint> out;
    if (!(total > 0.0)) return out;
    std::mt19937_64 rng(20261123);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    out.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        const std::size_t t = std::min(mesh.triangles.size() - 1,
                                       std::size_t(std::lower_bound(cumulative.begin(), cumulative.end(), unit(rng) * total) -
                                                   cumulative.begin()));
        double r1 = unit(rng), r2 = unit(rng);
        if (r1 + r2 > 1.0) r1 = 1.0 - r1, r2 = 1.0 - r2;
        const Mesh::Triangle& tri = mesh.triangles[t];
        const Vec3 &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
        const Vec3 area = glm::cross(b - a, c - a);
        const double l = glm::length(area);
        if (!(l > 0.0)) continue;
        out.push_back({a + r1 * (b - a) + r2 * (c - a), area / l});
    }
    return out;
}

/// Fails before any run where an output names a format it is not written in, cannot be written,
/// or would overwrite an input or another output.
void checkOutputs(const StudyOptions& o) {
    if (!o.csvPath.empty() && !takesFormat(o.csvPath, ".csv"))
        throw Error("output '" + o.csvPath + "': the table is written as .csv");
    if (!o.plotPath.empty() && !takesFormat(o.plotPath, ".png"))
        throw Error("output '" + o.plotPath + "': the plot is written as .png");
    checkSeparateFiles(jobInputFiles(o.job),
                       {{"--csv", o.csvPath}, {"--plot", o.plotPath}, {"--ply-deviation", o.plyDeviationDir}});
    for (const std::string* path : {&o.csvPath, &o.plotPath})
        if (!path->empty()) checkWritable(*path);
}

/// runSimulation(job), its errors prefixed with `which` run failed: the reference run's spacing is
/// one the user never typed. A program's own errors (ParseError) name their file and line already.
Simulation runNamed(const SimulateOptions& job, const std::string& which) {
    try {
        return runSimulation(job);
    } catch (const ParseError&) {
        throw;
    } catch (const Error& e) {
        throw Error(which + ": " + e.what());
    }
}

/// The mesh coloured as compare and simulate --deviation-ply colour theirs (deviationColour): red
/// where the model lacks material of the exact part (as a gouge), blue where it holds more (as
/// excess), with no tolerance between and darkest at one spacing; the distance as the property
/// deviation_mm.
void writeDeviationPly(const std::string& path, const Mesh& mesh, std::vector<double> deviation, double h,
                       OutputBatch& batch) {
    DeviationScale scale;
    scale.tolerance = {0.0, 0.0};
    scale.gougeFull = scale.excessFull = h;
    PlyVertexData data;
    data.colours = deviationColours(deviation, scale);
    data.scalarName = "deviation_mm";
    data.scalar = std::move(deviation);
    writePly(path, mesh, data, &batch);
}

}  // namespace

StudyResult runStudy(const StudyOptions& o) {
    if (o.resolutions.empty() || o.familySets.empty()) throw Error("a study needs spacings and family sets");
    for (double h : o.resolutions)
        if (!(h > 0)) throw Error("study spacings must be positive");
    if (!o.job.stockFile.empty())
        throw Error(o.job.stockFile + ": a study measures against the exact part cut from a box stock; an STL or "
                    "VDB stock is not supported (give the stock as box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX)");
    if (o.job.stockFrustum)
        throw Error("a study measures against the exact part cut from a box stock; a cylinder or cone stock is not "
                    "supported (give the stock as box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX)");
    checkPointsFit(o);
    checkOutputs(o);
    if (!o.plyDeviationDir.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(o.plyDeviationDir, ec);
        if (ec) throw Error(o.plyDeviationDir + ": cannot create the folder for deviation meshes: " + ec.message());
    }
    // Each spacing and each family set once, however often it was listed.
    std::vector<double> hs = o.resolutions;
    std::sort(hs.begin(), hs.end(), std::greater<double>());
    hs.erase(std::unique(hs.begin(), hs.end()), hs.end());
    std::vector<FamilySet> familySets;
    for (FamilySet f : o.familySets)
        if (std::none_of(familySets.begin(), familySets.end(), [&](FamilySet g) { return g.mask == f.mask; }))
            familySets.push_back(f);
    // The measurements use the job's thread count too.
    tbb::task_arena arena(arenaThreads(o.job.threads));
    // Every file, the runs' deviation meshes too, is staged, and renamed only once all are written.
    OutputBatch outputs;

    StudyResult result;
    result.subject = o.job.inputs.empty() ? std::string("program in memory") : o.job.inputs.front();
    const std::size_t total = hs.size() * familySets.size() + (o.exactVolumeMm3 ? 0 : 1);
    std::size_t done = 0;
    auto tick = [&](const char* stage) {
        if (o.progress) o.progress(stage, done, total);
    };

    // The reference volume: exact when known, else a tri-dexel run at half the finest spacing.
    std::optional<MachinedSolidOracle> oracle;
    if (o.exactVolumeMm3) {
        result.referenceVolumeMm3 = *o.exactVolumeMm3;
        result.reference = "exact";
    } else {
        tick("reference");
        SimulateOptions ref = o.job;
        ref.resolution = hs.back() / 2;
        ref.families = FamilySet::all();
        ref.progress = nullptr;
        std::ostringstream which;
        which << "the study's reference run, at half the finest of --resolutions (h = " << ref.resolution << " mm)";
        const Simulation s = runNamed(ref, which.str());
        result.referenceVolumeMm3 = s.stock->volume(Axis::Z);
        std::ostringstream r;
        r << "tri-dexel at h = " << ref.resolution << " mm";
        result.reference = r.str();
        ++done;
    }

    for (double h : hs) {
        for (FamilySet fams : familySets) {
            tick("study");
            const auto t0 = std::chrono::steady_clock::now();
            SimulateOptions job = o.job;
            job.resolution = h;
            job.families = fams;
            job.progress = nullptr;
            resetPeakMemory();  // the peak of this run, not of the runs before it
            const double memoryBefore = currentMemoryMb();
            std::ostringstream which;
            which << "the study's run at h = " << h << " mm with " << fams.str() << " dexels";
            const Simulation s = runNamed(job, which.str());
            StudyRun run;
            run.h = h;
            run.families = fams.str();
            run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            run.peakMemoryMb = std::max(0.0, s.report.peakMemoryMb - memoryBefore);
            run.stockMemoryMb = double(s.report.stockMemoryBytes) / (1024.0 * 1024.0);
            // The model's part volume as its level set's mesh encloses it, so that every family set
            // is judged the same way (a lone family's dexel volume is its own measure).
            run.volumeMm3 = s.report.meshVolumeMm3;
            run.volumeErrorMm3 = run.volumeMm3 - result.referenceVolumeMm3;
            if (!oracle) oracle.emplace(s.report.stockBox, s.program.path, s.tools, hs.back() / 2);

            // Surface deviation at points spread over the triangles, along their normals.
            const std::vector<SurfacePoint> points = surfacePoints(s.mesh, o.surfacePoints);
            std::vector<double> dev(points.size());
            arena.execute([&] {
                tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size()), [&](const auto& r) {
                    for (std::size_t i = r.begin(); i < r.end(); ++i)
                        dev[i] = signedDistance(*oracle, points[i].p, points[i].n, kSearchSpacings * h);
                });
            });
            run.points = dev.size();
            const DeviationStats overall = deviationStats(dev);
            run.devMaxMm = overall.max, run.devRmsMm = overall.rms, run.devP95Mm = overall.p95;
            run.devMeanMm = overall.mean;
            // The same away from the stock box's faces, whose own sharp edges every mesh rounds.
            const Box& stockBox = s.report.stockBox;
            std::vector<double> inner;
            for (std::size_t i = 0; i < points.size(); ++i)
                if (faceDistance(stockBox, points[i].p) >= h) inner.push_back(dev[i]);
            run.innerPoints = inner.size();
            const DeviationStats in = deviationStats(inner);
            run.innerMaxMm = in.max, run.innerRmsMm = in.rms, run.innerP95Mm = in.p95;
            if (!o.plyDeviationDir.empty()) {
                // The PLY colours every vertex: each measured along its own normal.
                const std::vector<Vec3> normals = vertexNormals(s.mesh);
                std::vector<double> all(s.mesh.vertices.size(), 0.0);
                arena.execute([&] {
                    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, all.size()), [&](const auto& r) {
                        for (std::size_t v = r.begin(); v < r.end(); ++v)
                            if (normals[v] != Vec3(0.0))
                                all[v] = signedDistance(*oracle, s.mesh.vertices[v], normals[v], kSearchSpacings * h);
                    });
                });
                std::ostringstream name;
                name << o.plyDeviationDir << "/deviation_h" << h << "_" << run.families << ".ply";
                writeDeviationPly(name.str(), s.mesh, std::move(all), h, outputs);
            }

            // Lost and invented material at random points (the same points for every run). Points
            // within one spacing of the stock's faces are left out: there every family set's mesh
            // rounds the block's own edges by about h / 2, which says nothing of the machining.
            std::mt19937_64 rng(20261122);
            const Box& box = stockBox;
            std::uniform_real_distribution<double> ux(box.lo.x, box.hi.x), uy(box.lo.y, box.hi.y),
                uz(box.lo.z, box.hi.z);
            std::vector<Vec3> pts(o.samplePoints);
            for (Vec3& p : pts) p = Vec3(ux(rng), uy(rng), uz(rng));
            std::vector<SampleCounts> perPoint(pts.size());
            arena.execute([&] {
                tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pts.size()), [&](const auto& r) {
                    for (std::size_t i = r.begin(); i < r.end(); ++i) {
                        const Vec3& p = pts[i];
                        if (faceDistance(box, p) < h) continue;
                        const bool exact = oracle->inside(p);
                        const double phi = s.levelSet.valueAt(p);
                        const bool model = phi < 0;
                        SampleCounts& c = perPoint[i];
                        if (exact && !model) c.lost = 1, c.lostFar = phi > h;
                        if (!exact && model) c.invented = 1, c.inventedFar = phi < -h;
                    }
                });
            });
            SampleCounts sum;
            for (const SampleCounts& c : perPoint) {
                sum.lost += c.lost;
                sum.invented += c.invented;
                sum.lostFar += c.lostFar;
                sum.inventedFar += c.inventedFar;
            }
            const double perPointVolume = pts.empty() ? 0.0 : box.volume() / double(pts.size());
            run.lostMm3 = double(sum.lost) * perPointVolume;
            run.inventedMm3 = double(sum.invented) * perPointVolume;
            run.lostFarMm3 = double(sum.lostFar) * perPointVolume;
            run.inventedFarMm3 = double(sum.inventedFar) * perPointVolume;
            result.runs.push_back(run);
            ++done;
        }
    }
    tick("study");
    if (!o.csvPath.empty()) {
        const std::string csv = studyCsv(result);
        writeStreamAtomically(o.csvPath, [&](std::ostream& out) { out << csv; }, &outputs);
    }
    if (!o.plotPath.empty()) writeStudyPlot(o.plotPath, result, &outputs);
    outputs.commit();
    return result;
}

std::string studyCsv(const StudyResult& r) {
    std::ostringstream s;
    s << std::setprecision(8);
    s << "h_mm,families,points,dev_max_mm,dev_rms_mm,dev_p95_mm,dev_max_h,dev_rms_h,dev_p95_h,dev_mean_mm,"
         "volume_mm3,volume_error_mm3,volume_error_rel,lost_mm3,invented_mm3,lost_far_mm3,invented_far_mm3,"
         "seconds,peak_memory_mb,stock_memory_mb,inner_points,inner_max_mm,inner_rms_mm,inner_p95_mm\n";
    for (const StudyRun& x : r.runs) {
        s << x.h << ',' << x.families << ',' << x.points << ',' << x.devMaxMm << ',' << x.devRmsMm << ','
          << x.devP95Mm << ',' << x.devMaxMm / x.h << ',' << x.devRmsMm / x.h << ',' << x.devP95Mm / x.h << ','
          << x.devMeanMm << ',' << x.volumeMm3 << ',' << x.volumeErrorMm3 << ','
          << (r.referenceVolumeMm3 != 0 ? x.volumeErrorMm3 / r.referenceVolumeMm3 : 0.0) << ',' << x.lostMm3 << ','
          << x.inventedMm3 << ',' << x.lostFarMm3 << ',' << x.inventedFarMm3 << ',' << x.seconds << ','
          << x.peakMemoryMb << ',' << x.stockMemoryMb << ',' << x.innerPoints << ',' << x.innerMaxMm << ','
          << x.innerRmsMm << ',' << x.innerP95Mm << '\n';
    }
    return s.str();
}

}  // namespace dexelmill
