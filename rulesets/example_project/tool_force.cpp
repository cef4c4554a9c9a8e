// A program that links fmpc::runtime (docs/runtime.md): it loads the tool scene, presses the instrument's tip 3 mm
// into the tissue and slides it 1 cm across, posing it every millisecond as a haptic loop would, and prints the
// force the tissue pushes back with; then it swaps the material for the rule file given (the clinician's last
// edit) between two steps and prints the force again.
//   tool_force SCENE.yaml [RULES.fis]
#include <algorithm>
#include <cstdio>

#include "runtime/session/session.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: tool_force SCENE.yaml [RULES.fis]\n");
    return 2;
  }
  fmpc::DiagnosticList diagnostics;
  const auto session = fmpc::runtime::Session::open(argv[1], diagnostics);
  if (!session) {
    std::fputs(fmpc::render_all(diagnostics, fmpc::SourceFiles{}).c_str(), stderr);
    return 2;
  }
  const std::size_t tip = *session->find_tool("tip");
  const fmpc::runtime::Point3 start = session->tool_poses()[tip].position;
  const double tick = 1e-3;  // s, a haptic device's period
  const auto report = [&] {
    const fmpc::runtime::ToolReading reading = session->tool_readings(diagnostics)[tip];
    std::printf("t %.3f s  tip (%.4f, %.4f) m  force (%.4f, %.4f, %.4f) N  contacts %zu\n", session->time(),
                session->tool_poses()[tip].position[0], session->tool_poses()[tip].position[2], reading.force[0],
                reading.force[1], reading.force[2], reading.contacts);
  };
  for (int t = 1; t <= 300; ++t) {
    // 3 mm down over the first 100 ms, then 1 cm along x over the next 200 ms.
    fmpc::runtime::ToolPose pose;
    pose.position = start;
    pose.position[2] -= 0.003 * std::min(1.0, t / 100.0);
    pose.position[0] += 0.01 * std::max(0.0, (t - 100) / 200.0);
    if (!session->set_tool_pose(tip, pose, diagnostics) || !session->step_to(t * tick, diagnostics)) {
      std::fputs(session->render(diagnostics).c_str(), stderr);
      return 1;
    }
    if (t % 50 == 0) report();
  }
  if (argc > 2) {
    if (!session->swap_material(argv[2], diagnostics)) {
      std::fputs(session->render(diagnostics).c_str(), stderr);
      return 1;
    }
    if (!session->step_to(session->time() + 0.05, diagnostics)) {
      std::fputs(session->render(diagnostics).c_str(), stderr);
      return 1;
    }
    std::printf("material swapped for %s\n", argv[2]);
    report();
  }
  return 0;
}
