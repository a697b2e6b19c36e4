// Cost of loading a mesh asset: parse + validation + surface/adjacency extraction.
// Run: build/tests/bench/bench_mesh
#include <benchmark/benchmark.h>

#include <string>

#include "torsion/mesh/mesh_io.h"

namespace {

void BM_ReadCylinder(benchmark::State& state, const std::string& name) {
  const std::string path = std::string(TORSION_ASSETS_DIR) + "/" + name;
  for (auto _ : state) {
    torsion::Result<torsion::LoadedMesh> loaded = torsion::readMesh(path);
    if (!loaded) {
      state.SkipWithError(loaded.error().message.c_str());
      return;
    }
    benchmark::DoNotOptimize(loaded.value().mesh.surfaceTriangleCount());
    state.counters["tets"] = loaded.value().mesh.tetCount();
  }
}

BENCHMARK_CAPTURE(BM_ReadCylinder, cylinder_8332, std::string("cylinder_8332.node"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadCylinder, cylinder_31558, std::string("cylinder_31558.node"))
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
