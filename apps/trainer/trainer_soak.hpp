#pragma once
// phaco-trainer --soak (issue 18 item 7): the trainer left running drill after drill, as a
// training station runs all day. After each drill it samples what would grow if something
// leaked: the process's resident memory, the GL objects alive in the context (counted by asking
// GL about every name, not from our own bookkeeping, so ImGui's and the renderer's are in it),
// and the haptic thread's period over that drill. phaco-perf soak charts and checks the samples.
//
// Main (GL) thread only.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace phaco::trainer {

struct SoakSample {
  int drill_index = 0;  // 0-based, in the order run
  std::string drill;
  double wall_s = 0;  // since the soak started, when the drill finished
  double rss_mb = 0;  // VmRSS, MiB
  int gl_buffers = 0, gl_vertex_arrays = 0, gl_textures = 0, gl_programs = 0, gl_framebuffers = 0;
  double haptic_period_p99_us = 0, haptic_period_max_us = 0;
  bool haptic_fifo = false;        // the haptic thread got SCHED_FIFO for this drill
  double render_frame_p99_ms = 0;  // the render loop over this drill
  double score = 0;                // the drill's score (a sanity check that drills really ran)
};

// Resident memory of this process, MiB (0 when /proc is unreadable).
double resident_mb();

// Fills the GL counts of `s` by probing names 1..max_name of each kind in the current context.
void count_gl_objects(SoakSample& s, unsigned max_name = 4096);

// The drill after `drill` in the soak's cycle: capsulorhexis → phaco_sculpting →
// corneal_incision → capsulorhexis.
std::string next_soak_drill(const std::string& drill);

// {"samples": [...], "soak_for_s": ...}; throws InputError naming the file it cannot write.
void write_soak(const std::filesystem::path& file, const std::vector<SoakSample>& samples,
                double soak_for_s);

}  // namespace phaco::trainer
