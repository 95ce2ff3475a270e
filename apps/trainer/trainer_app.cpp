// The window, its input and the frame loop in one file on purpose: they share one GLFW/ImGui
// context and its callbacks' glue (InputGlue); what the trainer writes is in trainer_files.
#include "apps/trainer/trainer_app.hpp"

// GLFW must not pull in a GL header: libepoxy provides the GL declarations.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>
#include <imgui_internal.h>  // the panels' rectangles, for the clutch

#include <algorithm>
#include <array>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "apps/trainer/trainer_files.hpp"
#include "apps/trainer/trainer_procedure.hpp"
#include "apps/trainer/trainer_settings.hpp"
#include "apps/trainer/trainer_soak.hpp"
#include "apps/trainer/trainer_ui.hpp"
#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"
#include "engine/haptics/loop_stats.hpp"
#include "engine/records/background_sync.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/record_run.hpp"
#include "engine/render/offscreen.hpp"
#include "engine/render/renderer.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/trainer/pointer_clutch.hpp"
#include "procedures/trainer/trainer_session.hpp"

namespace phaco::trainer {

namespace {

// Frame times of the render loop, for --stats (kept on the main thread; the loop's own figure).
struct FrameClock {
  std::vector<double> ms;
  int64_t start_ns = now_ns(), last_ns = now_ns();
  void tick() {
    const int64_t t = now_ns();
    ms.push_back(static_cast<double>(t - last_ns) * 1e-6);
    last_ns = t;
  }
  double percentile(double p) const {
    if (ms.empty()) return 0;
    std::vector<double> s = ms;
    std::sort(s.begin(), s.end());
    return s[std::min(s.size() - 1, static_cast<size_t>(p * static_cast<double>(s.size())))];
  }
};

struct Glfw {
  Glfw() {
    glfwSetErrorCallback([](int code, const char* text) {
      std::fprintf(stderr, "phaco-trainer: GLFW error %d: %s\n", code, text);
    });
    if (!glfwInit()) {
      throw render::RenderError(
          "cannot open a display (is DISPLAY set? on a machine without one, run under xvfb-run, "
          "or use the headless demo: phaco run data/scenarios/capsulorhexis_expert.json)");
    }
  }
  ~Glfw() { glfwTerminate(); }
};

// Mouse, wheel, keys and gamepad → the session's DesktopInput (the main thread is its one writer).
struct InputGlue {
  PointerClutch clutch;
  double wheel = 0;  // accumulated by the scroll callback
  bool tab_down = false, space_down = false, r_down = false, g_down = false, f1_down = false;
  bool f12_down = false;
  bool save_view = false;   // F12 was pressed: save the view this frame
  int views_saved = 0;      // by F12 in this run (view-NNN numbers them)
  int64_t ui_state_ns = 0;  // when --ui-state was last written
};

// The panels shown last frame (every ImGui window, popups included), in window pixels.
void panel_rects(std::vector<render::PixelRect>& out) {
  out.clear();
  for (const ImGuiWindow* w : ImGui::GetCurrentContext()->Windows)
    if (w->Active && !w->Hidden)
      out.push_back({w->Pos.x, w->Pos.y, w->Pos.x + w->Size.x, w->Pos.y + w->Size.y});
}

// Whether (x, y) px lies on a panel: there the pointer works the panel, not the tool.
bool over_panel(const std::vector<render::PixelRect>& panels, double x, double y) {
  for (const render::PixelRect& r : panels)
    if (x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1) return true;
  return false;
}

// Where the view is hidden under the panels (opaque and square: start_imgui, render_panels), in
// framebuffer pixels.
void covered_by_panels(const std::vector<render::PixelRect>& panels,
                       std::vector<render::PixelRect>& out) {
  const ImVec2 k = ImGui::GetIO().DisplayFramebufferScale;
  out.clear();
  for (const render::PixelRect& p : panels)
    out.push_back({p.x0 * k.x, p.y0 * k.y, p.x1 * k.x, p.y1 * k.y});
}

// ImGui's draw lists, each window's background first as a flat opaque rectangle of `bg` (ImGui's
// own is turned off in start_imgui): on llvmpipe a blended, textured panel background costs
// several times the flat one. List by list, so a window in front still covers the one behind.
void render_panels(render::Renderer& renderer, const std::array<float, 4>& bg, int fb_w, int fb_h) {
  const ImDrawData* all = ImGui::GetDrawData();
  const ImVec2 k = all->FramebufferScale;
  for (int i = 0; i < all->CmdListsCount; ++i) {
    ImDrawList* list = all->CmdLists[i];
    const ImGuiWindow* w = list->_OwnerName ? ImGui::FindWindowByName(list->_OwnerName) : nullptr;
    constexpr ImGuiWindowFlags kOwnBg =
        ImGuiWindowFlags_ChildWindow | ImGuiWindowFlags_Popup | ImGuiWindowFlags_Tooltip;
    if (w && w->Active && !w->Hidden && !w->Collapsed && !(w->Flags & kOwnBg)) {
      // Where ImGui puts it: below the title bar.
      const render::PixelRect r{w->Pos.x * k.x, (w->Pos.y + w->TitleBarHeight()) * k.y,
                                (w->Pos.x + w->Size.x) * k.x, (w->Pos.y + w->Size.y) * k.y};
      renderer.fill({&r, 1}, bg, fb_w, fb_h);
    }
    ImDrawData one = *all;
    one.CmdLists = &list;
    one.CmdListsCount = 1;
    one.TotalVtxCount = list->VtxBuffer.Size;
    one.TotalIdxCount = list->IdxBuffer.Size;
    ImGui_ImplOpenGL3_RenderDrawData(&one);
  }
}

// The panels' font: DejaVu Sans (Debian's fonts-dejavu-core) has the range and unit signs
// (≥ – ° µ) the Result table prints; without it ImGui's built-in font (ASCII and Latin-1). Its
// glyphs are rasterised at the pixel grid (no horizontal oversampling, snapped advances), as the
// built-in font's are, so the atlas can be sampled nearest (start_imgui).
void load_font() {
  static const ImWchar kRanges[] = {0x0020, 0x00FF, 0x2013, 0x2014, 0x2264, 0x2265, 0};
  const char* const path = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  ImFontConfig config;
  config.OversampleH = 1;
  config.PixelSnapH = true;
  if (std::filesystem::exists(path))
    ImGui::GetIO().Fonts->AddFontFromFileTTF(path, 14.0f, &config, kRanges);
}

InputGlue* glue_of(GLFWwindow* w) {
  return static_cast<InputGlue*>(glfwGetWindowUserPointer(w));
}

bool pressed_once(GLFWwindow* w, int key, bool& was_down) {
  const bool down = glfwGetKey(w, key) == GLFW_PRESS;
  const bool edge = down && !was_down;
  was_down = down;
  return edge;
}

TrainerConfig config_of(const TrainerOptions& o) {
  TrainerConfig c;
  c.scenario = load_scenario(o.scenario);
  if (!o.difficulty.empty()) c.scenario.difficulty = o.difficulty;
  // The drill file and the level are checked now, before a window opens.
  resolve_difficulty(load_drill_for(c.scenario), c.scenario.difficulty,
                     c.scenario.difficulty_settings, c.scenario.source);
  c.devices = {o.left, o.right};
  // A trainee's hands need time; a scripted drill ends with its script.
  const auto scripted = [](const std::string& d) {
    return d == "scripted" || d == "track" || d.rfind("replay:", 0) == 0;
  };
  c.duration_s = o.duration_s > 0                        ? o.duration_s
                 : scripted(o.left) && scripted(o.right) ? 0.0
                                                         : 900.0;
  c.scene.threads = o.threads;
  c.scene.cache_dir = o.cache_dir;
  c.trainee = o.trainee;
  c.records_db = o.db;
  return c;
}

// One procedure step's session as --stats sees it (each step runs in its own session: its own
// frame count and haptic loop).
struct StepStatus {
  std::string drill;
  TrainerStatus status;
  size_t render_frames = 0;  // drawn while the step ran
  double wall_s = 0;         // from the step's start (its scene's build included)
  // The step's haptic period histogram whole (a copy), so --stats can pool every tick of the
  // procedure (write_stats); shared, as StepStatus lists are copied.
  std::shared_ptr<const DurationHistogram> haptic_period;
  int64_t spin_margin_start_ns = 0;  // the margin the step's loop started from (0: the floor)
};

// Why a haptic period ran long: the wake-up's lateness, the tick's own compute, the spin before
// the deadline, and deadlines skipped (engine/haptics/loop_stats.hpp), in µs.
nlohmann::json haptic_loop_json(const TrainerStatus& s) {
  const auto summary = [](const DurationSummary& d) {
    return nlohmann::json{
        {"count", d.count}, {"p50_us", d.p50_us}, {"p99_us", d.p99_us}, {"max_us", d.max_us}};
  };
  const LoopStatsSnapshot& l = s.haptic_loop;
  return {{"fifo", s.haptic_fifo},         {"overruns", l.overruns},
          {"period", summary(l.period)},   {"lateness", summary(l.lateness)},
          {"compute", summary(l.compute)}, {"spin", summary(l.spin)}};
}

nlohmann::json step_json(const StepStatus& st) {
  const TrainerStatus& s = st.status;
  return {{"drill", st.drill},
          {"wall_s", st.wall_s},
          {"render_frames", st.render_frames},
          {"fps", st.wall_s > 0 ? static_cast<double>(st.render_frames) / st.wall_s : 0.0},
          {"sim_frames", s.frame},
          {"sim_time_s", s.sim_time_s},
          {"haptic_period_p50_us", s.haptic_period_p50_us},
          {"haptic_period_p99_us", s.haptic_period_p99_us},
          {"haptic_ticks", s.haptic_ticks},
          {"haptic_loop", haptic_loop_json(s)},
          // The loop's spin margin (docs/haptic_loop.md) as the step began and as it left it:
          // the next step starts from the latter.
          {"haptic_spin_margin_start_us", static_cast<double>(st.spin_margin_start_ns) * 1e-3},
          {"haptic_spin_margin_end_us", static_cast<double>(s.haptic_spin_margin_ns) * 1e-3},
          {"snapshots_published", s.snapshots_published}};
}

// `steps`: a procedure's sessions so far, the one in progress last (empty for a drill). Over a
// procedure the simulation's frames and haptic ticks are the steps' sums, and the haptic period's
// p50/p99/max are pooled over every tick of every step (the steps' histograms merged: issue 20's
// "p99 over the procedure"); the worst step's p99 is written beside it, and each step's own
// figures are under "steps".
void write_stats(const std::filesystem::path& file, const TrainerOptions& o, const FrameClock& fc,
                 const TrainerStatus& current, double wall_s,
                 const std::vector<StepStatus>& steps = {}) {
  TrainerStatus s = current;
  DurationSummary pooled;
  double worst_step_p99_us = 0;
  if (!steps.empty()) {
    s.frame = 0, s.sim_time_s = 0, s.haptic_ticks = 0, s.snapshots_published = 0;
    DurationHistogram all_ticks;
    for (const StepStatus& st : steps) {
      s.frame += st.status.frame;
      s.sim_time_s += st.status.sim_time_s;
      s.haptic_ticks += st.status.haptic_ticks;
      s.snapshots_published += st.status.snapshots_published;
      if (st.haptic_period) all_ticks.merge(*st.haptic_period);
      worst_step_p99_us = std::max(worst_step_p99_us, st.status.haptic_period_p99_us);
    }
    pooled = all_ticks.summary();
    s.haptic_period_p50_us = pooled.p50_us;
    s.haptic_period_p99_us = pooled.p99_us;
  }
  nlohmann::json j;
  j["width"] = o.width;
  j["height"] = o.height;
  j["render"] = o.render;
  j["renderer"] = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  j["frames"] = fc.ms.size();
  j["wall_s"] = wall_s;
  j["fps"] = wall_s > 0 ? static_cast<double>(fc.ms.size()) / wall_s : 0.0;
  j["frame_p50_ms"] = fc.percentile(0.5);
  j["frame_p99_ms"] = fc.percentile(0.99);
  j["sim_time_s"] = s.sim_time_s;
  j["sim_frames"] = s.frame;
  j["sim_rate_hz"] = wall_s > 0 ? static_cast<double>(s.frame) / wall_s : 0.0;
  j["haptic_period_p50_us"] = s.haptic_period_p50_us;
  j["haptic_period_p99_us"] = s.haptic_period_p99_us;
  j["haptic_ticks"] = s.haptic_ticks;
  if (steps.empty()) j["haptic_loop"] = haptic_loop_json(s);  // a procedure's: per step
  if (!steps.empty()) {
    j["haptic_period_max_us"] = pooled.max_us;
    j["haptic_period_count"] = pooled.count;  // the periods pooled: the steps' counts summed
    j["haptic_period_worst_step_p99_us"] = worst_step_p99_us;
  }
  j["snapshots_published"] = s.snapshots_published;
  if (!steps.empty()) {
    j["steps"] = nlohmann::json::array();
    for (const StepStatus& st : steps) j["steps"].push_back(step_json(st));
  }
  std::ofstream out(file);
  out << j.dump(2) << "\n";
  if (!out) throw InputError(file.string() + ": cannot write the statistics");
}

// A soak run's sample of the drill that just ended (its report r): memory, GL objects, the
// haptic period, the render frames since the drill began (frame0) and its score.
SoakSample soak_sample(const nlohmann::json& r, const std::string& drill, size_t index,
                       double wall_s, const FrameClock& frames, size_t frame0) {
  SoakSample s;
  s.drill_index = static_cast<int>(index);
  s.drill = drill;
  s.wall_s = wall_s;
  s.rss_mb = resident_mb();
  count_gl_objects(s);
  const nlohmann::json period = r.contains("live")
                                    ? r["live"]["haptics"].value("period", nlohmann::json())
                                    : nlohmann::json();
  s.haptic_period_p99_us = period.is_object() ? period.value("p99_us", 0.0) : 0.0;
  s.haptic_period_max_us = period.is_object() ? period.value("max_us", 0.0) : 0.0;
  if (r.contains("live"))
    s.haptic_fifo =
        r["live"]["haptics"].value("realtime", nlohmann::json::object()).value("fifo", false);
  FrameClock drill_frames;
  drill_frames.ms.assign(frames.ms.begin() + static_cast<std::ptrdiff_t>(frame0), frames.ms.end());
  s.render_frame_p99_ms = drill_frames.percentile(0.99);
  s.score = r.value("metrics", nlohmann::json::object()).value("score", 0.0);
  return s;
}

// One frame's input into the session's DesktopInput (read by the haptic thread through the hands'
// devices) and the keys. The clutch: the pointer drives the tool only over the view (inside the
// window, on no panel).
void read_input(GLFWwindow* window, InputGlue& glue, const TrainerOptions& o,
                TrainerSession& session, render::Renderer& renderer, TrainerUi& ui,
                const FrameClock& frames, const std::vector<render::PixelRect>& panels) {
  const bool ui_has_mouse = o.ui && ImGui::GetIO().WantCaptureMouse;
  const bool ui_has_keys = o.ui && ImGui::GetIO().WantCaptureKeyboard;

  DesktopInput& in = session.desktop();
  double x = 0, y = 0;
  glfwGetCursorPos(window, &x, &y);
  int win_w = 0, win_h = 0;
  glfwGetWindowSize(window, &win_w, &win_h);
  const bool in_view =
      x >= 0 && y >= 0 && x < win_w && y < win_h && !ui_has_mouse && !over_panel(panels, x, y);
  const bool clutch_held = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS ||
                           glfwGetKey(window, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                           glfwGetKey(window, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
  const auto [dx, dy] = clutch_step(glue.clutch, x, y, in_view, clutch_held);
  if (dx != 0 || dy != 0) in.mouse_move(dx, dy);
  if (glue.wheel != 0 && in_view) in.wheel(glue.wheel);
  glue.wheel = 0;
  if (in_view) {
    in.mouse_buttons(glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS,
                     glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS);
  }
  if (glfwJoystickIsGamepad(GLFW_JOYSTICK_1)) {
    GLFWgamepadstate g;
    if (glfwGetGamepadState(GLFW_JOYSTICK_1, &g)) {
      GamepadState pad;
      for (int i = 0; i < 6; ++i) pad.axes[static_cast<size_t>(i)] = g.axes[i];
      for (int i = 0; i < 15; ++i) pad.buttons[static_cast<size_t>(i)] = g.buttons[i] == GLFW_PRESS;
      in.gamepad(pad, frames.ms.empty() ? 0.0 : frames.ms.back() * 1e-3);
    }
  }
  if (!ui_has_keys) {
    if (pressed_once(window, GLFW_KEY_TAB, glue.tab_down)) in.switch_hand();
    if (pressed_once(window, GLFW_KEY_SPACE, glue.space_down)) {
      session.state() == TrainerState::Paused ? session.resume() : session.pause();
    }
    if (pressed_once(window, GLFW_KEY_R, glue.r_down)) session.reset();
    if (pressed_once(window, GLFW_KEY_G, glue.g_down))
      renderer.options().guidance = !renderer.options().guidance;
    if (pressed_once(window, GLFW_KEY_F1, glue.f1_down)) ui.toggle_controls();
    if (pressed_once(window, GLFW_KEY_F12, glue.f12_down)) glue.save_view = true;
  }
}

// Closing with drills the database refused: never lose them silently. Beside the database first;
// where that folder is the problem (read-only, full), the temp folder. False when neither took
// them.
bool keep_unsaved(TrainerSession& session, const TrainerConfig& config) {
  if (session.unsaved_count() == 0) return true;
  std::vector<std::filesystem::path> dirs;
  try {
    const auto db = config.records_db.empty() ? default_records_db() : config.records_db;
    if (!is_postgres_uri(db.string())) dirs.push_back(db.parent_path() / "unsaved");
  } catch (const InputError&) {
  }
  dirs.push_back(std::filesystem::temp_directory_path() / "openphaco-unsaved");
  std::string why;
  bool kept = false;
  for (const auto& dir : dirs) {
    try {
      for (const auto& f : session.write_unsaved(dir))
        std::fprintf(stderr, "phaco-trainer: an unsaved drill is kept in %s\n", f.c_str());
      kept = true;
      break;
    } catch (const InputError& e) {
      why += std::string(why.empty() ? "" : "; ") + e.what();
    }
  }
  if (!kept)
    std::fprintf(stderr, "phaco-trainer: unsaved drills could not be kept: %s\n", why.c_str());
  return kept;
}

// The trainer's window with an OpenGL 3.3 core context, its input routed to `glue`.
GLFWwindow* open_window(const TrainerOptions& o, InputGlue& glue) {
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  GLFWwindow* window = glfwCreateWindow(o.width, o.height, "OpenPhaco trainer", nullptr, nullptr);
  if (!window) throw render::RenderError("cannot create an OpenGL 3.3 core window");
  glfwMakeContextCurrent(window);
  // Unattended runs measure and capture as fast as the renderer goes; a trainee gets v-sync.
  glfwSwapInterval(o.screenshot || o.stats || o.soak ? 0 : 1);
  glfwSetWindowUserPointer(window, &glue);
  glfwSetScrollCallback(window, [](GLFWwindow* w, double, double dy) { glue_of(w)->wheel += dy; });
  // A key tapped between two frames (a slow software-rendered frame, or a synthetic key) still
  // reads as pressed once: glfwGetKey keeps the press until it is read.
  glfwSetInputMode(window, GLFW_STICKY_KEYS, GLFW_TRUE);
  return window;
}

// Dear ImGui on the window: no imgui.ini beside the user's files, the panels' font. Returns the
// panels' background colour, which render_panels draws.
std::array<float, 4> start_imgui(GLFWwindow* window, const TrainerOptions& o) {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
  // Opaque panels, so the renderer can leave the view under them unshaded (covered_by_panels).
  ImGuiStyle& style = ImGui::GetStyle();
  for (ImGuiCol c : {ImGuiCol_WindowBg, ImGuiCol_PopupBg, ImGuiCol_TitleBgCollapsed})
    style.Colors[c].w = 1.0f;
  const ImVec4 bg = style.Colors[ImGuiCol_WindowBg];
  style.Colors[ImGuiCol_WindowBg].w = 0.0f;  // ImGui draws none: render_panels does
  style.WindowRounding = 0.0f;               // as render_panels and covered_by_panels draw them
  if (o.ui) load_font();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 330");
  // Tab switches hands (read_input). ImGui's tabbing also took it, putting a focused panel's
  // first field (a slider or a text field) into text entry, after which every key (F12, Space,
  // R…) went to the field, not to the trainer. Panels are worked with the mouse.
  ImGui::GetIO().KeyMap[ImGuiKey_Tab] = -1;
  // Every glyph and panel lands on whole pixels (ImGui floors text and window positions), so the
  // atlas sampled nearest draws what bilinear filtering would, for a quarter of llvmpipe's texel
  // fetches; lines are anti-aliased by geometry, not by filtering the atlas's baked lines.
  ImGui_ImplOpenGL3_CreateDeviceObjects();
  glBindTexture(GL_TEXTURE_2D,
                static_cast<GLuint>(reinterpret_cast<intptr_t>(ImGui::GetIO().Fonts->TexID)));
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glBindTexture(GL_TEXTURE_2D, 0);
  style.AntiAliasedLinesUseTex = false;
  return {bg.x, bg.y, bg.z, 1.0f};
}

// The next drill (or procedure step) in a new session; drills the database refused stay kept.
void restart_session(std::unique_ptr<TrainerSession>& session, const TrainerConfig& config) {
  auto next = std::make_unique<TrainerSession>(config);
  next->take_unsaved_from(*session);
  session = std::move(next);
  session->start();
}

}  // namespace

int run_trainer(const TrainerOptions& o) {
  TrainerConfig config = config_of(o);  // bad scenario / level: InputError before any window
  // --procedure: its steps in turn, each on the eye the steps before it left.
  const std::unique_ptr<ProcedureDriver> procedure = start_procedure(o, config);
  // So are bad device specs and trainee names (the session checks them without building anything).
  auto session = std::make_unique<TrainerSession>(config);
  Glfw glfw;
  InputGlue glue;
  GLFWwindow* window = open_window(o, glue);
  const std::array<float, 4> panel_bg = start_imgui(window, o);

  int exit_code = 0;
  {
    render::RenderOptions ro;
    ro.stereo = o.stereo ? render::StereoMode::SideBySide : render::StereoMode::Mono;
    ro.guidance = o.guidance;
    render::Renderer renderer(ro);
    render::Microscope microscope;
    session->start();
    TrainerUi ui(o, config);
    // Offline-first (issue 21): drills are stored here, then uploaded to the centre in the
    // background; the worker outlives every drill's session and stops with the window.
    std::unique_ptr<BackgroundSync> sync;
    if (!o.sync_to.empty()) {
      sync = std::make_unique<BackgroundSync>(
          config.records_db.empty() ? default_records_db() : config.records_db, o.sync_to);
      ui.set_sync(sync.get());
    }
    FrameClock frames;
    std::vector<render::PixelRect> panels, covered;  // last frame's panels; the view they hide
    const int64_t t0 = now_ns();
    const auto wall_s = [&] { return static_cast<double>(now_ns() - t0) * 1e-9; };

    // --soak: the drill in progress, where its render frames start, and the samples so far.
    std::string soak_drill(to_string(config.scenario.drill));
    size_t soak_frame0 = 0;
    std::vector<SoakSample> soak_samples;
    // --procedure: the steps' sessions that are over, for --stats, and where the current began.
    std::vector<StepStatus> procedure_steps;
    size_t step_frame0 = 0;
    double step_wall0 = 0;
    const auto this_step = [&] {
      auto period = std::make_shared<DurationHistogram>();
      session->merge_haptic_period_into(*period);
      TrainerStatus status = session->status();
      // The step's period figures from the very copy that is pooled (the loop may still be
      // ticking): the steps' counts then add up to the pooled count exactly.
      status.haptic_loop.period = period->summary();
      status.haptic_period_p50_us = status.haptic_loop.period.p50_us;
      status.haptic_period_p99_us = status.haptic_loop.period.p99_us;
      return StepStatus{std::string(to_string(config.scenario.drill)),
                        std::move(status),
                        frames.ms.size() - step_frame0,
                        wall_s() - step_wall0,
                        std::move(period),
                        session->config().haptics.loop.start_margin_ns};
    };
    const auto steps_so_far = [&] {
      std::vector<StepStatus> steps = procedure_steps;
      steps.push_back(this_step());
      return steps;
    };

    while (!glfwWindowShouldClose(window)) {
      glfwPollEvents();
      // The Result panel finishes a drill that ended (Idle after), unless this loop got there
      // first (Ended): either way the drill is over.
      if (procedure && procedure->close_when_done()) {
        // A scripted procedure ended before --stats-after: its figures are the whole procedure's.
        if (o.stats) {
          write_stats(*o.stats, o, frames, session->status(), wall_s(), steps_so_far());
          std::printf("statistics at the procedure's end, %.1f s: %s\n", wall_s(),
                      o.stats->c_str());
        }
        break;
      }
      if (procedure && procedure->step_over(*session)) {
        procedure_steps.push_back(this_step());
        step_frame0 = frames.ms.size();
        step_wall0 = wall_s();
        config = procedure->step_config(config);
        // The next step's haptic loop starts from the spin margin this one learned (set here, the
        // one place a step's session follows another's): the machine, the renderer and the load
        // it saw are the same, and a fresh loop at the 60 µs floor relearns a loaded machine
        // only by waking late first (docs/haptic_loop.md, "A margin that follows the latency").
        config.haptics.loop.start_margin_ns = procedure_steps.back().status.haptic_spin_margin_ns;
        restart_session(session, config);
        ui = TrainerUi(o, config);  // the next step's panels, its Result not yet shown
        ui.set_sync(sync.get());
        continue;
      }
      if (const TrainerState st = session->state();
          o.soak && (st == TrainerState::Ended || st == TrainerState::Idle)) {
        // A drill ended: sample, then the next drill in a new session, as a station runs.
        const nlohmann::json r =
            st == TrainerState::Ended ? session->finish() : session->last_report();
        const SoakSample s =
            soak_sample(r, soak_drill, soak_samples.size(), wall_s(), frames, soak_frame0);
        soak_samples.push_back(s);
        std::printf("soak: drill %d (%s) done at %.0f s: %.1f MiB, %d buffers, %d textures\n",
                    s.drill_index, s.drill.c_str(), s.wall_s, s.rss_mb, s.gl_buffers,
                    s.gl_textures);
        std::fflush(stdout);
        if (wall_s() >= o.soak_for_s) {
          write_soak(*o.soak, soak_samples, o.soak_for_s);
          std::printf("soak: %zu drills in %.0f s: %s\n", soak_samples.size(), wall_s(),
                      o.soak->c_str());
          break;
        }
        soak_drill = next_soak_drill(soak_drill);
        config.scenario = load_scenario(drill_scenario(soak_drill));
        restart_session(session, config);
        soak_frame0 = frames.ms.size();
        continue;
      }
      if (glfwGetKey(window, GLFW_KEY_ESCAPE) == GLFW_PRESS) glfwSetWindowShouldClose(window, 1);
      if (o.ui) {
        panel_rects(panels);
        covered_by_panels(panels, covered);
      }
      read_input(window, glue, o, *session, renderer, ui, frames, panels);

      // The view: the newest snapshot the simulation published.
      int fb_w = 0, fb_h = 0;
      glfwGetFramebufferSize(window, &fb_w, &fb_h);
      glViewport(0, 0, fb_w, fb_h);
      glClearColor(0.02f, 0.02f, 0.03f, 1.0f);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      const render::RenderSnapshot* snap = session->newest_snapshot();
      const TrainerStatus status = session->status();
      if (!status.error.empty()) throw InputError("simulation stopped: " + status.error);

      // After the simulated time, or at the drill's end if it is shorter.
      if (o.screenshot && snap &&
          (status.sim_time_s >= o.after_s || status.state == TrainerState::Ended)) {
        save_view(renderer, *snap, microscope, o.width, o.height, *o.screenshot);
        std::printf("screenshot at %.2f s simulated (%.1f s wall): %s\n", status.sim_time_s,
                    wall_s(), o.screenshot->c_str());
        break;
      }
      if (glue.save_view && snap) {
        glue.save_view = false;
        char name[32];
        std::snprintf(name, sizeof name, "view-%03d", glue.views_saved + 1);
        const std::filesystem::path png = o.views_dir / (std::string(name) + ".png");
        try {  // a folder that refuses the file costs the picture, not the drill
          save_view(renderer, *snap, microscope, fb_w, fb_h, png);
          write_view_poses(o.views_dir / (std::string(name) + ".json"), *snap, microscope,
                           status.sim_time_s, fb_w, fb_h);
          ++glue.views_saved;
          std::printf("view saved: %s\n", png.c_str());
        } catch (const std::exception& e) {
          std::fprintf(stderr, "phaco-trainer: F12: the view was not saved: %s\n", e.what());
        }
        glViewport(0, 0, fb_w, fb_h);
      }
      if (snap && o.render) renderer.draw(*snap, microscope, fb_w, fb_h, covered);

      if (o.ui) {
        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        if (procedure) procedure->draw_panel();
        if (ui.draw(*session, renderer, microscope, frames.ms.empty() ? 0.0 : frames.ms.back(),
                    snap, fb_w, fb_h) == UiAction::Restart) {
          config = ui.config();
          restart_session(session, config);
        }
        ImGui::Render();
        render_panels(renderer, panel_bg, fb_w, fb_h);
        if (o.ui_state && now_ns() - glue.ui_state_ns > 100'000'000) {
          nlohmann::json state = ui.state_json(*session, session->newest_snapshot());
          state["views_saved"] = glue.views_saved;
          write_json_file(*o.ui_state, state);
          glue.ui_state_ns = now_ns();
        }
      }
      glfwSwapBuffers(window);
      frames.tick();

      if (o.stats && wall_s() >= o.stats_after_s) {
        write_stats(*o.stats, o, frames, session->status(), wall_s(),
                    procedure ? steps_so_far() : std::vector<StepStatus>{});
        std::printf("statistics after %.1f s: %s\n", wall_s(), o.stats->c_str());
        break;
      }
      if ((o.screenshot || o.stats || o.soak) && wall_s() > o.timeout_s) {
        std::fprintf(stderr,
                     "phaco-trainer: timed out after %.0f s wall (simulated %.2f s of %.2f s)\n",
                     wall_s(), status.sim_time_s,
                     o.screenshot ? o.after_s
                     : o.soak     ? o.soak_for_s
                                  : o.stats_after_s);
        exit_code = 3;
        break;
      }
    }
    session->stop();
    if (!keep_unsaved(*session, config) && exit_code == 0) exit_code = 2;
  }
  // An interactive drill's choices, for the next (trainer_settings.hpp); not a procedure's step.
  if (!procedure) remember_settings(o, config);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  return exit_code;
}

}  // namespace phaco::trainer
