// `uwbnav eval report|nlos|family ...` and `uwbnav train-svm ...`: evaluation and training front ends.
#include <cstdio>
#include <cstring>

#include "tools/eval/eval_family.hpp"
#include "tools/eval/eval_nlos.hpp"
#include "tools/eval/eval_outage.hpp"
#include "tools/eval/eval_rtk.hpp"
#include "tools/eval/report.hpp"
#include "tools/eval/svm_train.hpp"

namespace uwbnav::cli {

int cmd_eval(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "report") == 0) return eval::run_eval_report(argc - 1, argv + 1);
  if (argc >= 2 && std::strcmp(argv[1], "nlos") == 0) return eval::run_eval_nlos(argc - 1, argv + 1);
  if (argc >= 2 && std::strcmp(argv[1], "family") == 0) return eval::run_eval_family(argc - 1, argv + 1);
  if (argc >= 2 && std::strcmp(argv[1], "outage") == 0) return eval::run_eval_outage(argc - 1, argv + 1);
  if (argc >= 2 && std::strcmp(argv[1], "rtk") == 0) return eval::run_eval_rtk(argc - 1, argv + 1);
  std::fprintf(stderr,
               "usage: uwbnav eval report RECORDING... --out DIR [--jobs N] [--no-figures]\n"
               "       uwbnav eval nlos [options]   (seed 000 Table 2 form; see docs/nlos.md)\n"
               "       uwbnav eval family [--cells a,b] [--seeds tuning|reporting|N-M] [--fast] [--markdown] ...\n"
               "                          (scenario family, accuracy with honesty; see docs/evaluation.md)\n"
               "       uwbnav eval outage [--seeds tuning|reporting|N-M] [--drives K] [--markdown] ...\n"
               "                          (error during UWB outages with and without the RBF bridge; see docs/ekf.md)\n"
               "       uwbnav eval rtk [--seeds tuning|reporting|N-M] [--runs N] [--slip-rate HZ] [--markdown]\n"
               "                          (carrier-phase baseline, BDS only vs BDS + UWB; see docs/lambda.md)\n");
  return 2;
}

int cmd_train_svm(int argc, char** argv) { return eval::run_train_svm(argc, argv); }

}  // namespace uwbnav::cli
