#include "cylinder_mesher.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ostream>
#include <set>
#include <utility>

#include "tetgen_runner.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion::meshgen {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxRuns = 40;
// Quality bound for every cylinder: radius-edge ratio 1.4 and a minimum dihedral angle of 12 deg.
constexpr const char* kQuality = "1.4/12";

// How a surface with point spacing h tends to behave under tetgen -q (measured, not derived):
// for max volumes between ~0.5 h^3 and ~0.9 h^3 the quality refinement alone decides the count
// (the coarsest count for that surface); below ~0.13 h^3 tetgen starts splitting the surface
// itself and the count jumps by about 2x. Between 0.15 h^3 and 0.5 h^3 the count varies smoothly
// enough with the max volume to be searched.
constexpr double kCoarseVolume = 0.5;
constexpr double kFineVolume = 0.15;

struct Surface {
  int segments = 0;
  int layers = 0;
  bool operator<(const Surface& o) const {
    return std::make_pair(segments, layers) < std::make_pair(o.segments, o.layers);
  }
  bool operator==(const Surface& o) const { return segments == o.segments && layers == o.layers; }
};

int clampedCount(double x, int lo, int hi) {
  if (!(x < hi)) return hi;  // also catches NaN
  return std::max(lo, static_cast<int>(std::lround(x)));
}

class CylinderSearch {
 public:
  CylinderSearch(const fs::path& tetgen, const CylinderSpec& spec, const fs::path& dir,
                 std::ostream* log)
      : tetgen_(tetgen), spec_(spec), dir_(dir), log_(log) {}

  Surface surfaceFor(double h) const {
    return {clampedCount(2 * kPi * spec_.radius / h, 6, 20000),
            clampedCount(spec_.length / h, 1, 20000)};
  }

  bool done() const {
    return best_tets_ >= 0 && std::abs(best_tets_ - spec_.target_tets) <= 0.01 * spec_.target_tets;
  }
  bool outOfRuns() const { return runs_ >= kMaxRuns; }

  Result<int> run(double h, double max_volume) {
    const Surface s = surfaceFor(h);
    const fs::path input = dir_ / "cylinder.smesh";
    if (!(s == written_)) {
      Status ok =
          writeTextFile(input, cylinderSmesh(spec_.radius, spec_.length, s.segments, s.layers));
      if (!ok) return ok.error();
      written_ = s;
    }
    const std::string switches = cylinderSwitches(max_volume);
    Result<TetgenRun> r = runTetgen(tetgen_, switches, input);
    ++runs_;
    if (!r) return r.error();
    const int tets = r.value().tets;
    if (log_ != nullptr) {
      char line[160];
      std::snprintf(line, sizeof line, "  tetgen run %2d: %d segments x %d layers, %s -> %d tets\n",
                    runs_, s.segments, s.layers, switches.c_str(), tets);
      *log_ << line << std::flush;
    }
    if (best_tets_ < 0 ||
        std::abs(tets - spec_.target_tets) < std::abs(best_tets_ - spec_.target_tets)) {
      std::error_code ec;
      fs::rename(r.value().node, dir_ / "best.node", ec);
      if (!ec) fs::rename(r.value().ele, dir_ / "best.ele", ec);
      if (ec) return Error{"cannot keep tetgen's output in " + dir_.string() + ": " + ec.message()};
      best_tets_ = tets;
      best_surface_ = s;
      best_volume_ = max_volume;
      best_switches_ = switches;
    }
    return tets;
  }

  enum class Verdict { kDone, kTooFine, kTooCoarse, kMissed };

  // For the surface of spacing h: are the reachable counts above, below or around the target?
  // Around: search the max volume (regula falsi on log count against log volume).
  Result<Verdict> searchVolume(double h) {
    const double target = spec_.target_tets;
    const double h3 = h * h * h;
    Result<int> coarse = run(h, kCoarseVolume * h3);
    if (!coarse) return coarse.error();
    if (done()) return Verdict::kDone;
    if (coarse.value() > target) return Verdict::kTooFine;
    Result<int> fine = run(h, kFineVolume * h3);
    if (!fine) return fine.error();
    if (done()) return Verdict::kDone;
    if (fine.value() < target) return Verdict::kTooCoarse;

    // lo: more tets than the target (smaller volume); hi: fewer.
    double lo_x = std::log(kFineVolume * h3), lo_y = std::log(fine.value());
    double hi_x = std::log(kCoarseVolume * h3), hi_y = std::log(coarse.value());
    for (int i = 0; i < 6 && !outOfRuns() && hi_x - lo_x > 0.02; ++i) {
      double t = hi_y != lo_y ? (std::log(target) - lo_y) / (hi_y - lo_y) : 0.5;
      t = std::clamp(t, 0.15, 0.85);
      const double x = lo_x + t * (hi_x - lo_x);
      Result<int> count = run(h, std::exp(x));
      if (!count) return count.error();
      if (done()) return Verdict::kDone;
      if (count.value() > target) {
        lo_x = x;
        lo_y = std::log(count.value());
      } else {
        hi_x = x;
        hi_y = std::log(count.value());
      }
    }
    return Verdict::kMissed;
  }

  // Outer search over the surface spacing: bracket it between a spacing that gives too many tets
  // and one that gives too few, then bisect over the surfaces (integer ring counts) between them.
  Status search() {
    const double volume = kPi * spec_.radius * spec_.radius * spec_.length;
    double h = std::cbrt(16 * volume / spec_.target_tets);
    double h_fine = 0, h_coarse = 0;  // 0: not known yet
    std::set<Surface> tried;
    while (!outOfRuns()) {
      tried.insert(surfaceFor(h));
      Result<Verdict> verdict = searchVolume(h);
      if (!verdict) return verdict.error();
      if (verdict.value() == Verdict::kDone) return Ok{};
      if (verdict.value() == Verdict::kTooFine) {
        h_fine = h;
        if (h_coarse > 0 && h_coarse <= h_fine) h_coarse = 0;
      } else if (verdict.value() == Verdict::kTooCoarse) {
        h_coarse = h;
        if (h_fine > 0 && h_fine >= h_coarse) h_fine = 0;
      }
      if (verdict.value() == Verdict::kMissed || h_fine == 0 || h_coarse == 0) {
        // Step to a surface not tried yet: finer when the counts were too low, coarser when too
        // high, a nudge when the target fell in a jump of this surface's counts.
        const double step =
            verdict.value() == Verdict::kMissed ? 0.985 : (h_fine > 0 ? 1.15 : 1 / 1.15);
        for (int k = 0; k < 200 && tried.count(surfaceFor(h)) > 0; ++k)
          h *= step;
        if (tried.count(surfaceFor(h)) > 0) return Ok{};
        continue;
      }
      bool found = false;
      while (h_coarse / h_fine > 1.0005) {
        const double mid = std::sqrt(h_fine * h_coarse);
        const Surface s = surfaceFor(mid);
        if (s == surfaceFor(h_fine) || (!(s == surfaceFor(h_coarse)) && tried.count(s) > 0)) {
          h_fine = mid;
        } else if (s == surfaceFor(h_coarse)) {
          h_coarse = mid;
        } else {
          h = mid;
          found = true;
          break;
        }
      }
      if (!found) return Ok{};
    }
    return Ok{};
  }

  int runs() const { return runs_; }
  Surface bestSurface() const { return best_surface_; }
  double bestVolume() const { return best_volume_; }
  const std::string& bestSwitches() const { return best_switches_; }

 private:
  const fs::path& tetgen_;
  const CylinderSpec& spec_;
  const fs::path& dir_;
  std::ostream* log_;
  int runs_ = 0;
  Surface written_{};
  int best_tets_ = -1;
  Surface best_surface_{};
  double best_volume_ = 0;
  std::string best_switches_;
};

}  // namespace

std::string cylinderSwitches(double max_volume) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "-pq%sa%.6gFQ", kQuality, max_volume);
  return buffer;
}

std::string cylinderSmesh(double radius, double length, int segments, int layers) {
  std::string text;
  char buffer[160];
  std::snprintf(buffer, sizeof buffer,
                "# torsion mesh cylinder: radius %.17g, length %.17g, %d segments, %d layers\n",
                radius, length, segments, layers);
  text += buffer;
  const int rings = layers + 1;
  std::snprintf(buffer, sizeof buffer, "%d 3 0 0\n", rings * segments);
  text += buffer;
  for (int k = 0; k < rings; ++k) {
    const double z = k == layers ? length : length * k / layers;
    for (int i = 0; i < segments; ++i) {
      const double angle = 2 * kPi * i / segments;
      std::snprintf(buffer, sizeof buffer, "%d %.17g %.17g %.17g\n", k * segments + i,
                    radius * std::cos(angle), radius * std::sin(angle), z);
      text += buffer;
    }
  }
  std::snprintf(buffer, sizeof buffer, "%d 0\n", 2 + segments * layers);
  text += buffer;
  // Bottom cap (normal -z: clockwise seen from +z), top cap, then the side quads.
  text += std::to_string(segments);
  for (int i = segments - 1; i >= 0; --i)
    text += " " + std::to_string(i);
  text += "\n" + std::to_string(segments);
  for (int i = 0; i < segments; ++i)
    text += " " + std::to_string(layers * segments + i);
  text += "\n";
  for (int k = 0; k < layers; ++k) {
    for (int i = 0; i < segments; ++i) {
      const int j = (i + 1) % segments;
      std::snprintf(buffer, sizeof buffer, "4 %d %d %d %d\n", k * segments + i, k * segments + j,
                    (k + 1) * segments + j, (k + 1) * segments + i);
      text += buffer;
    }
  }
  text += "0\n0\n";  // no holes, no regions
  return text;
}

Result<CylinderMesh> meshCylinder(const fs::path& tetgen, const CylinderSpec& spec,
                                  const fs::path& work_dir, std::ostream* log) {
  CylinderSearch search(tetgen, spec, work_dir, log);
  Status searched = search.search();
  if (!searched) return searched.error();
  if (search.runs() == 0) return Error{"the cylinder search ran no tetgen"};
  Result<LoadedMesh> loaded = readMesh(work_dir / "best.node");
  if (!loaded) return Error{"reading tetgen's output: " + loaded.error().message};
  CylinderMesh result{std::move(loaded).value(),   search.bestSurface().segments,
                      search.bestSurface().layers, search.bestVolume(),
                      search.bestSwitches(),       search.runs()};
  return result;
}

}  // namespace torsion::meshgen
