#include "check_command.h"

#include <iostream>
#include <memory>

#include "mesh_command.h"
#include "run_comparison.h"
#include "torsion/device/json_check.h"
#include "verbosity.h"

namespace torsion::cli {

namespace {

struct CheckArguments {
  std::string run;
  std::string reference;
  ComparisonTolerance tolerance;
};

int check(const CheckArguments& args) {
  Result<RunComparison> compared = compareRuns(args.run, args.reference, args.tolerance);
  if (!compared) {
    std::cerr << "error: " << device::printableExcerpt(compared.error().message, 400) << "\n";
    return 1;
  }
  const RunComparison& c = compared.value();
  if (verbosity() != Verbosity::kQuiet) {  // --quiet: the verdict only
    for (const std::string& line : c.report)
      std::cout << device::printableExcerpt(line, 400) << "\n";
  }
  if (c.differences == 0) {
    std::cout << "same: " << args.run << " matches " << args.reference << " within "
              << args.tolerance.relative << " relative, " << args.tolerance.absolute
              << " absolute\n";
    return 0;
  }
  std::cout << "DIFFERENT: " << c.differences
            << (c.differences == 1 ? " difference" : " differences") << " between " << args.run
            << " and " << args.reference << " beyond " << args.tolerance.relative << " relative, "
            << args.tolerance.absolute << " absolute\n";
  return 2;
}

}  // namespace

void addCheckCommand(CLI::App& app, CommandAction& chosen) {
  auto args = std::make_shared<CheckArguments>();
  CLI::App* cmd = app.add_subcommand(
      "check",
      "Compare a run's outputs (summary.json, CSVs, final meshes) with a reference run's; exit 0 "
      "when they agree within the tolerance, 2 when they differ");
  cmd->add_option("run", args->run, "Output directory of the run to check")->required();
  cmd->add_option("reference", args->reference, "Output directory of the reference run")
      ->required();
  cmd->add_option("--tolerance", args->tolerance.relative,
                  "Relative tolerance: of each value's scale (a CSV column's largest magnitude, "
                  "a body's size)")
      ->check(CLI::Range(0.0, 1.0).description("a number from 0 to 1"))
      ->capture_default_str();
  cmd->add_option("--absolute-tolerance", args->tolerance.absolute,
                  "Absolute tolerance, in each value's unit")
      ->check(CLI::Range(0.0, 1e30).description("a number from 0 to 1e30"))
      ->capture_default_str();
  cmd->callback([&chosen, args] { chosen = [args] { return check(*args); }; });
}

}  // namespace torsion::cli
