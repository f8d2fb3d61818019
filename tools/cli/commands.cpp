// The table of `uwbnav` subcommands.
#include "tools/cli/commands.hpp"

namespace uwbnav::cli {

int cmd_sim(int argc, char** argv);
int cmd_replay(int argc, char** argv);
int cmd_run(int argc, char** argv);
int cmd_params(int argc, char** argv);
int cmd_eval(int argc, char** argv);
int cmd_train_svm(int argc, char** argv);
int cmd_firmware(int argc, char** argv); int cmd_hil(int argc, char** argv);
int cmd_calibrate(int argc, char** argv);

const std::vector<Command>& commands() {
  static const std::vector<Command> table = {
      {"run", "main job: simulate the default scenario, run the firmware loop, print the result table", cmd_run},
      {"sim", "simulate a scenario into a format v1 recording: sim SCENARIO|family:CELL:SEED --out DIR [--seed N]", cmd_sim},
      {"replay", "run the firmware loop in lockstep over a recording: replay DIR --out OUT", cmd_replay},
      {"eval", "evaluation: eval report RECORDING... --out DIR | eval nlos (NLOS tables) | eval family (scenario family, honesty)", cmd_eval},
      {"train-svm", "train the NLOS SVM with libsvm and export the firmware model (docs/nlos.md)", cmd_train_svm},
      {"firmware", "the firmware as a real-time host process (recording or HIL CAN sensors)", cmd_firmware}, {"hil", "HIL bench: play a recording into a firmware over CAN, report latency/jitter/drops/error", cmd_hil},
      {"params", "print the parameter table (--markdown: docs/parameters.md)", cmd_params},
      {"calibrate", "per anchor/tag range offsets from recordings into a site calibration file (docs/commissioning.md)",
       cmd_calibrate},
  };
  return table;
}

}  // namespace uwbnav::cli
