#pragma once
// `torsion run --vtk-every N` (scene key "vtk_every") and World.record_series in Python: a
// ParaView time series of the run in
// <out>/series.pvd, one .vtu per written step per body in <out>/series/:
//   <body>_<step>.vtu        FEM body: the nodes where they are; point data displacement (m) and
//                            velocity (m/s); cell data von_mises (Pa), strain (max |s_i - 1|,
//                            deformation_metrics.h) and inverted (1 when det F <= 0); tet4 as
//                            VTK_TETRA, tet10 as VTK_QUADRATIC_TETRA (then stress and strain are
//                            the element's: volume mean and maximum over its 8 sub-tets); field
//                            data TimeValue, step and the wrench [fx fy fz tx ty tz] of each node
//                            set and hand on the body ("wrench_<name>", N and N m)
//   rigid_<name>_<step>.vtu  rigid body: its surface (rigid_surface.h) in its pose; field data
//                            TimeValue, step, position (m) and orientation [qx qy qz qw]
// Steps s, s + N, s + 2N, ... from the step s it starts at, and the last step, are written. series/
// is emptied of .vtu files (and of the temporaries a killed run left of them) when a series starts;
// series.pvd is rewritten (whole) after each written step, so a stopped run leaves a series
// ParaView opens.

#include <memory>
#include <string>
#include <vector>

#include "scene_builder.h"
#include "torsion/result.h"
#include "vtu_writer.h"

namespace torsion::series {

class VtkSeries {
 public:
  /// Creates <out_dir>/series, empties it of .vtu files and writes `first_step` (the world's
  /// step count now). Errors name the directory or file.
  static Result<std::unique_ptr<VtkSeries>> start(const std::string& out_dir, int every,
                                                  const scene::BuiltScene& scene,
                                                  int first_step = 0);

  /// After step `step` of `total` (-1: open-ended): writes it when it is due (every N-th from
  /// the first, or the last). Errors name the file.
  Status onStep(const scene::BuiltScene& scene, int step, int total);

  /// The end of the series at step `step`: writes it unless it was the last written.
  Status finish(const scene::BuiltScene& scene, int step);

  /// Rewrites <out_dir>/series.pvd listing the steps written so far (writeStep does after each).
  Status writeIndex() const;

  int stepsWritten() const { return steps_written_; }

 private:
  VtkSeries(std::string out_dir, int every, int first_step)
      : out_dir_(std::move(out_dir)), every_(every), first_step_(first_step) {}
  /// Step `step`'s files and the rewritten series.pvd.
  Status writeStep(const scene::BuiltScene& scene, int step);
  Status write(const scene::BuiltScene& scene, int step);

  std::string out_dir_;
  int every_ = 1;
  int first_step_ = 0;
  int last_written_ = -1;  ///< the step last written, or -1
  int steps_written_ = 0;
  std::vector<PvdEntry> entries_;
};

}  // namespace torsion::series
