#include "perf/trainer_run.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "engine/core/error.hpp"

namespace phaco::perf {

namespace fs = std::filesystem;

fs::path trainer_binary() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const fs::path bin = self.parent_path().parent_path() / "apps" / "phaco-trainer";
  if (ec || !fs::exists(bin)) {
    throw InputError("trainer: phaco-trainer not found at " + bin.string() +
                     " (build the target phaco-trainer)");
  }
  return bin;
}

double load_1min() {
  std::ifstream in("/proc/loadavg");
  double one = -1;
  return in >> one ? one : -1.0;
}

namespace {

// Cumulative CPU seconds of a process's threads: main (tid = pid), llvmpipe-*, the rest.
struct CpuSample {
  double t = 0, main = 0, llvmpipe = 0, other = 0;
};

bool sample_cpu(pid_t pid, CpuSample& s) {
  static const double tick = static_cast<double>(sysconf(_SC_CLK_TCK));
  std::error_code ec;
  bool any = false;
  for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec)) {
    std::ifstream in(task.path() / "stat");
    std::string st;
    if (!std::getline(in, st)) continue;
    const size_t open = st.find('('), close = st.rfind(')');
    if (open == std::string::npos || close == std::string::npos) continue;
    const std::string comm = st.substr(open + 1, close - open - 1);
    std::istringstream f(st.substr(close + 2));
    std::string field;
    double utime = 0, stime = 0;
    for (int k = 0; k < 13 && f >> field; ++k) {
      if (k == 11) utime = std::atof(field.c_str());
      if (k == 12) stime = std::atof(field.c_str());
    }
    const double c = (utime + stime) / tick;
    any = true;
    if (task.path().filename() == std::to_string(pid)) {
      s.main += c;
    } else if (comm.rfind("llvmpipe", 0) == 0) {
      s.llvmpipe += c;
    } else {
      s.other += c;
    }
  }
  return any;
}

// The trainer started under `session` (xvfb-run's session): the process running `bin`.
pid_t find_trainer(const fs::path& bin, pid_t session) {
  std::error_code ec;
  const fs::path want = fs::canonical(bin, ec);
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    const std::string name = e.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::error_code ec2;
    if (fs::read_symlink(e.path() / "exe", ec2) != want || ec2) continue;
    std::ifstream in(e.path() / "stat");
    std::string st;
    if (!std::getline(in, st)) continue;
    std::istringstream f(st.substr(st.rfind(')') + 2));
    std::string field;
    for (int k = 0; k < 4 && f >> field; ++k) {
    }
    if (std::atoi(field.c_str()) == session) return static_cast<pid_t>(std::stoi(name));
  }
  return -1;
}

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Runs `cmd` in a session of its own; while the trainer runs, samples its threads' CPU every
// 50 ms until `stats` appears. Returns the shell's exit status.
int run_sampled(const std::string& cmd, const fs::path& bin, const fs::path& stats,
                std::vector<CpuSample>& samples) {
  const pid_t child = fork();
  if (child < 0) return -1;
  if (child == 0) {
    setsid();
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  pid_t trainer = -1;
  int status = 0;
  for (;;) {
    if (waitpid(child, &status, WNOHANG) == child) break;
    if (trainer < 0) trainer = find_trainer(bin, child);
    CpuSample s{.t = now_s()};
    if (trainer > 0 && !fs::exists(stats) && sample_cpu(trainer, s)) samples.push_back(s);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TrainerRun run_trainer(const fs::path& bin, const fs::path& dir, const std::string& name,
                       const std::string& what, const std::string& tail, bool render,
                       const std::optional<fs::path>& data_dir, RenderCpu* cpu) {
  const fs::path out = dir / ("trainer_" + name + (render ? "" : "_norender") + ".stats.json");
  fs::remove(out);
  const std::string env = data_dir ? "PHACO_DATA_DIR='" + data_dir->string() + "' " : "";
  const std::string cmd = env + "xvfb-run -a -s '-screen 0 " + std::to_string(kTrainerWidth) + "x" +
                          std::to_string(kTrainerHeight) + "x24' '" + bin.string() + "' " + what +
                          " --left scripted --right scripted --size " +
                          std::to_string(kTrainerWidth) + "x" + std::to_string(kTrainerHeight) +
                          " --stats " + out.string() + " " + tail + (render ? "" : " --no-render") +
                          " > /dev/null 2>&1";
  const double before = load_1min();
  std::vector<CpuSample> samples;
  const int rc = cpu ? run_sampled(cmd, bin, out, samples) : std::system(cmd.c_str());
  const double after = load_1min();
  if (rc != 0 || !fs::exists(out)) {
    throw InputError("trainer: `" + cmd + "` failed (exit " + std::to_string(rc) +
                     "); is xvfb-run installed (scripts/install-deps.sh)?");
  }
  std::ifstream in(out);
  TrainerRun r{name, render, nlohmann::json::parse(in), before, after};
  if (cpu && !samples.empty()) {
    // The stats cover the last wall_s seconds before the file appeared; skip their first 3 s.
    const double wall = r.stats.value("wall_s", 0.0), frames = r.stats.value("frames", 0.0);
    const CpuSample& b = samples.back();
    const double start = b.t - wall + 3.0;
    const auto a = std::find_if(samples.begin(), samples.end(),
                                [&](const CpuSample& s) { return s.t >= start; });
    if (a != samples.end() && b.t - a->t > 1.0 && wall > 0 && frames > 0) {
      const double n = frames * (b.t - a->t) / wall;  // frames in the sampled window
      *cpu = {.main_ms = 1e3 * (b.main - a->main) / n,
              .llvmpipe_ms = 1e3 * (b.llvmpipe - a->llvmpipe) / n,
              .other_ms = 1e3 * (b.other - a->other) / n,
              .window_s = b.t - a->t,
              .measured = true};
    }
  }
  return r;
}

TrainerRun run_trainer_drill(const fs::path& bin, const fs::path& dir, const std::string& drill,
                             bool render, double seconds, const std::optional<fs::path>& data_dir,
                             const std::string& name, RenderCpu* cpu) {
  TrainerRun r = run_trainer(
      bin, dir, name.empty() ? drill : name, "--drill " + drill,
      "--duration " + std::to_string(seconds + 30) + " --stats-after " + std::to_string(seconds),
      render, data_dir, cpu);
  r.drill = drill;
  return r;
}

}  // namespace phaco::perf
