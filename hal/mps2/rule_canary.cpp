// Deliberate rule violations (heap, soft-double) linked only into the
// uwbnav_mps2_canary image, so that a test proves image_analysis.py check
// catches them; never part of the firmware image.
#include <cstdlib>

namespace uwbnav::mps2::canary {

volatile float g_sink_float = 0.0F;
void* volatile g_sink_block = nullptr;

__attribute__((noinline)) double scale_in_double(double x) { return x * 1.000001 + 2.5; }

// Entry point the test names as the "hot path" root.
void hot_path(float x) {
  g_sink_float = static_cast<float>(scale_in_double(static_cast<double>(x)));
  g_sink_block = std::malloc(16);  // kept: a malloc/free pair would be optimised away
}

}  // namespace uwbnav::mps2::canary
