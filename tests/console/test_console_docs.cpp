// docs/console.md shows console sessions that are the output of the code: each
// block between "<!-- session NAME -->" and "<!-- /session -->" is produced
// here by typing the session's commands into the firmware on a lockstep replay
// of the simulated parking_nlos drive, and compared with the document.
// Regenerate after a change: UWBNAV_UPDATE_DOCS=1 ctest --preset host -R ConsoleDocs
#include <gtest/gtest.h>

#include <cctype>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "console_rig.hpp"

namespace uwbnav {
namespace {

using testing::ConsoleRig;
using testing::sim_recording;
using testing::split_lines;

struct Step {
  std::string typed;   // a line typed at the console ("" for none)
  double wait_s = 0;   // then the firmware runs this long (streams, a moving vehicle)
};

struct Session {
  const char* name;
  double start_s;      // drive time before the first command
  std::vector<Step> steps;
};

// Types each line and runs cycles until its reply is out (prompt back, nothing
// queued); returns the screen as a terminal shows it.
std::string run_session(const Session& s) {
  ConsoleRig rig(sim_recording());
  rig.run_s(s.start_s);
  rig.serial.output.clear();
  bool echo = true;
  for (const Step& step : s.steps) {
    if (!step.typed.empty()) {
      rig.serial.type(step.typed + "\r");
      if (step.typed == "echo off") echo = false;
      const size_t before = rig.serial.output.size();
      for (int n = 0; n < 1000; ++n) {
        rig.tick();
        const bool prompt = rig.serial.output.size() >= 2 && rig.serial.output.compare(rig.serial.output.size() - 2, 2, "> ") == 0;
        if (rig.serial.pending_input() == 0 && rig.app.console().tx_pending() == 0 && !rig.app.console().busy() &&
            (prompt || (!echo && rig.serial.output.size() > before))) {
          break;
        }
      }
    }
    if (step.wait_s > 0) rig.run_s(step.wait_s);
  }
  // The prompt of the cycle before the session began starts the screen; trailing
  // blanks and empty last lines are left out.
  std::vector<std::string> lines = split_lines("> " + rig.serial.output + "\r\n");
  while (!lines.empty() && (lines.back().empty() || lines.back() == "> ")) lines.pop_back();
  std::string screen;
  for (std::string& line : lines) {
    while (!line.empty() && line.back() == ' ') line.pop_back();
    screen += line + "\n";
  }
  // The build's git hash changes with every commit: the document shows a placeholder.
  // (A hand-written scan: GCC 12 warns inside <regex> under ASan.)
  std::string out;
  size_t pos = 0;
  for (size_t at = screen.find("git=", pos); at != std::string::npos; at = screen.find("git=", pos)) {
    size_t end = at + 4;
    while (end < screen.size() && std::isxdigit(static_cast<unsigned char>(screen[end])) &&
           !std::isupper(static_cast<unsigned char>(screen[end]))) {
      ++end;
    }
    out.append(screen, pos, at + 4 - pos);
    out += end > at + 4 ? "<hash>" : "";
    pos = end;
  }
  out.append(screen, pos, std::string::npos);
  return out;
}

const std::vector<Session>& sessions() {
  static const std::vector<Session> all = {
      {"terminal", 40.0,
       {{"status"},
        {"anchors"},
        {"ekf"},
        {"param get gate.innov_sigma"},
        {"param set gate.innov_sigma 250"},
        {"param set gate.policy 3.5"},
        {"param set gate.innov_sigma 8"},
        {"param list gate.innov*"},
        {"param list -c"},
        {"frobnicate"},
        {"stream pos 2", 1.0},
        {"stream off"}}},
      {"resets", 20.0,
       {{"version"},
        {"reset filter", 2.0},
        {"status"},
        {"stats"},
        {"reset stats"},
        {"stats"}}},
      {"script", 42.6, {{"echo off"}, {"status"}}},
  };
  return all;
}

std::string read_text(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

TEST(ConsoleDocs, ExampleSessionsInConsoleMdAreTheOutputOfTheCode) {
#ifdef UWBNAV_ESTIMATOR_DOUBLE
  GTEST_SKIP() << "the document shows the float estimator's numbers";
#endif
  const std::string path = std::string(UWBNAV_SOURCE_DIR) + "/docs/console.md";
  std::string doc = read_text(path);
  ASSERT_FALSE(doc.empty()) << path;
  const bool update = std::getenv("UWBNAV_UPDATE_DOCS") != nullptr;
  for (const Session& s : sessions()) {
    const std::string open = std::string("<!-- session ") + s.name + " -->\n```\n";
    const std::string close = "```\n<!-- /session -->";
    const size_t b = doc.find(open);
    ASSERT_NE(b, std::string::npos) << "docs/console.md lacks the block " << open;
    const size_t e = doc.find(close, b);
    ASSERT_NE(e, std::string::npos) << "unterminated block " << s.name;
    const std::string shown = doc.substr(b + open.size(), e - b - open.size());
    const std::string generated = run_session(s);
    if (update) {
      doc.replace(b + open.size(), shown.size(), generated);
    } else {
      EXPECT_EQ(shown, generated) << "docs/console.md session '" << s.name
                                  << "' is stale: UWBNAV_UPDATE_DOCS=1 ctest --preset host -R ConsoleDocs";
    }
  }
  if (update) std::ofstream(path) << doc;
}

}  // namespace
}  // namespace uwbnav
