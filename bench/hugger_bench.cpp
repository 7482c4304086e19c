// hugger_bench: plans fixed scenarios and reports where the time goes.
//
//   hugger_bench [--scenario NAME]... [--skin mesh|section|both] [--repeat R] [--json] [--list] [--no-fork]
//
// Every scenario is planned with each chosen skin (default both: the mesh world, the reference,
// and the section skin), side by side, with the ratio of their figures.
// Every scenario runs in a child process of its own (unless --no-fork), so that its peak
// memory (max RSS) is its own. Inputs (meshes, hands, poses) are generated before any clock
// starts. Figures are medians over the R repeats; per-iteration percentiles pool the Phase 2
// iterations of all repeats. Release builds only: a build without NDEBUG refuses to run
// unless --allow-debug is given, and then marks every figure as such.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>  // malloc_trim
#endif

#include "hugger/planner/planner.hpp"
#include "hugger/world/object.hpp"
#include "hugger/world/section_skin.hpp"
#include "hugger/world/simulated_world.hpp"
#include "meshes.hpp"  // tests/cpp: the icosphere and curvy, built as hugger.objects builds them
#include "scenes.hpp"  // tests/cpp: test::EmptySkin

using namespace hugger;
using Clock = std::chrono::steady_clock;

namespace {

#ifdef NDEBUG
constexpr bool kReleaseBuild = true;
#else
constexpr bool kReleaseBuild = false;
#endif

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// --- inputs ------------------------------------------------------------------------------

using test::Mesh;

Mesh sphere(double radius, int subdivisions) {
  Mesh m = test::icosphere(subdivisions);
  m.vertices *= radius;
  return m;
}

using test::curvy;

/// The paper-like start, as hugger.scenarios.start_pose(obj, hand, T, (0, 0, 1), turn_deg=60,
/// distance=0.2) builds it (the demo starts from the same direction at the safe distance,
/// nearer): look_at(T + (0, 0, 0.2), T), then turned 60 degrees
/// about the palm's own y axis (the rotation applied on the right of the palm's rotation).
Pose paper_start(const Vec3& target) {
  // look_at: z toward T; up (0, 0, 1) is parallel to z, so up = (1, 0, 0) as in look_at.
  const Vec3 position = target + Vec3(0.0, 0.0, 0.2);
  Vec3 z = target - position;
  z /= z.norm();
  Vec3 up(0.0, 0.0, 1.0);
  if (up.cross(z).norm() < 1e-6) up = std::abs(z.x()) < 0.9 ? Vec3(1.0, 0.0, 0.0) : Vec3(0.0, 1.0, 0.0);
  Vec3 x = up.cross(z);
  x /= x.norm();
  Mat3 R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  const double c = std::cos(60.0 * kPi / 180.0), s = std::sin(60.0 * kPi / 180.0);
  Mat3 turn;
  turn << c, 0, s, 0, 1, 0, -s, 0, c;
  Pose p = Pose::Identity();
  p.linear() = R * turn;
  p.translation() = position;
  return p;
}

struct Scenario {
  std::string name, object, hand;
  std::function<Mesh()> mesh;
  int fingers = 5, links = 5;
  double link_length = 0.02, link_radius = 0.004, palm_radius = 0.03, palm_thickness = 0.01;
};

std::vector<Scenario> scenarios() {
  std::vector<Scenario> out;
  auto paper_hand = [](Scenario s) {
    s.hand = "5x5 paper hand";
    return s;
  };
  out.push_back(paper_hand({"paper", "curvy, 20480 triangles", "", [] { return curvy(5); }}));
  const char* labels[] = {"1k", "20k", "80k", "320k", "1.3m"};
  const int subdivisions[] = {3, 5, 6, 7, 8};
  for (int i = 0; i < 5; ++i) {
    const int s = subdivisions[i];
    out.push_back(paper_hand({std::string("sphere-") + labels[i],
                              "sphere r 4 cm, " + std::to_string(20L << (2 * s)) + " triangles", "",
                              [s] { return sphere(0.04, s); }}));
  }
  // Hands of other sizes on curvy: the finger reach stays 10 cm (the paper hand's), the link
  // radius shrinks with short links (a link must be longer than 2 radii).
  for (int n : {2, 4, 8, 16, 32}) {
    Scenario s{"hand-N" + std::to_string(n), "curvy, 20480 triangles", "", [] { return curvy(5); }};
    s.links = n;
    s.link_length = 0.1 / n;
    s.link_radius = std::min(0.004, 0.2 * s.link_length);
    out.push_back(s);
  }
  for (int m : {2, 5, 8, 16}) {
    Scenario s{"hand-M" + std::to_string(m), "curvy, 20480 triangles", "", [] { return curvy(5); }};
    s.fingers = m;
    out.push_back(s);
  }
  for (auto& s : out) {
    std::ostringstream os;
    os << s.fingers << "x" << s.links << " L " << s.link_length * 1000 << " mm r " << s.link_radius * 1000 << " mm";
    s.hand = os.str();
  }
  return out;
}

// --- running -------------------------------------------------------------------------------

/// One scenario's figures, as plain data: a child process sends it through a pipe.
struct Result {
  char name[32] = {};
  char skin[12] = {};
  char status[24] = {};
  int repeats = 0;
  long triangles = 0, fingers = 0, links = 0;
  long configurations = 0, phase1_configurations = 0, phase2_iterations = 0;
  double object_s = 0, planner_s = 0, phase2_s = 0, total_s = 0;  // medians
  double sections_s = 0;  // section skin: building the regions of every finger plane (median)
  double iterations_per_s = 0;                                    // Phase 2 iterations / Phase 2 time
  double p50_us = 0, p90_us = 0, p99_us = 0, max_us = 0;           // per Phase 2 iteration, pooled
  double max_rss_mib = 0;
  double object_faults = 0, faults = 0;  // minor page faults (mostly fresh pages) of the Object's build, of a whole plan (medians)
  bool deterministic = true;
  std::uint64_t digest = 0;  // of the first repeat's plan: compare it across builds
  bool ok = false;
  char error[160] = {};
};

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double percentile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  const double at = q * static_cast<double>(sorted.size() - 1);
  const std::size_t i = static_cast<std::size_t>(at);
  const double f = at - static_cast<double>(i);
  return i + 1 < sorted.size() ? sorted[i] * (1 - f) + sorted[i + 1] * f : sorted[i];
}

/// FNV-1a over the bits of every emitted configuration: equal digests mean bit-identical plans.
std::uint64_t digest(const Planner& p) {
  std::uint64_t h = 1469598103934665603ULL;
  auto mix = [&h](const void* data, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ULL;
  };
  for (const Configuration& c : p.history()) {
    mix(c.palm.matrix().data(), sizeof(double) * 16);
    for (const Vec3& j : c.joints) mix(j.data(), sizeof(double) * 3);
    mix(c.tip_state.data(), c.tip_state.size());
  }
  return h;
}

/// This process's resource use so far (every thread).
rusage self_usage() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u;
}

/// Minor page faults so far: mostly the fresh pages touched (copy-on-write ones count too).
long minor_faults() { return self_usage().ru_minflt; }

double max_rss_mib() { return static_cast<double>(self_usage().ru_maxrss) / 1024.0; }  // KiB on Linux

std::shared_ptr<const Sensing> make_skin(const std::string& skin, const std::shared_ptr<const Object>& object) {
  if (skin == "section") return std::make_shared<SectionSkin>(object);
  return std::make_shared<SimulatedWorld>(object);
}

Result run(const Scenario& sc, const std::string& skin, int repeats) {
  Result r;
  std::snprintf(r.name, sizeof r.name, "%s", sc.name.c_str());
  std::snprintf(r.skin, sizeof r.skin, "%s", skin.c_str());
  r.repeats = repeats;
  r.fingers = sc.fingers;
  r.links = sc.links;
  try {
    const Mesh mesh = sc.mesh();  // inputs before any clock
    const HandModel hand = HandModel::uniform(sc.fingers, sc.links, sc.link_length, sc.link_radius, sc.palm_radius,
                                              sc.palm_thickness);
    const Vec3 target = Vec3::Zero();
    const Pose start = paper_start(target);
    r.triangles = mesh.faces.rows();
    std::vector<double> object_s, planner_s, phase2_s, total_s, sections_s, per_iteration, object_faults, faults;
    std::uint64_t first_digest = 0;
    // Room for the per-iteration times, reserved before the clocks and the faults window (its
    // pages are still first touched inside them: a few a repeat; the first repeat may grow it).
    std::size_t iterations = 4096;
    object_faults.reserve(static_cast<std::size_t>(repeats));
    faults.reserve(static_cast<std::size_t>(repeats));
    // The planes of Phase 2, where Phase 1 leaves the palm (the skin only checks Phase 1, so a
    // skin that senses nothing gives the same planes): the section skin's regions are built and
    // timed apart below, before the planner that would otherwise build them in its constructor
    // (SectionSkin::prepare) finds them built. The probe's memory goes back to the system, so
    // that the timed builds touch as many fresh pages as without it.
    std::vector<FingerPlane> planes;
    if (skin == "section") {
      planes = Planner(hand, std::make_shared<test::EmptySkin>(), target, start).planes();
#if defined(__GLIBC__)
      malloc_trim(0);
#endif
    }
    for (int k = 0; k < repeats; ++k) {
      per_iteration.reserve(per_iteration.size() + iterations);
      const long f0 = minor_faults();
      const auto t0 = Clock::now();
      auto object = std::make_shared<const Object>(mesh.vertices, mesh.faces);
      const double t_object = seconds_since(t0);
      object_faults.push_back(static_cast<double>(minor_faults() - f0));
      const std::shared_ptr<const Sensing> sensing = make_skin(skin, object);
      const auto* section = dynamic_cast<const SectionSkin*>(sensing.get());
      if (section) {
        // The finger planes' regions, as the planner's constructor builds them at the end of
        // Phase 1 (SectionSkin::prepare: side by side, one thread per region up to the hardware's).
        const auto ts = Clock::now();
        section->prepare(planes, hand.link_radius());
        sections_s.push_back(seconds_since(ts));
      }
      const int built = section ? section->regions() : 0;
      const auto t1 = Clock::now();
      Planner planner(hand, sensing, target, start);
      const double t_planner = seconds_since(t1);
      if (section && section->regions() != built)
        throw std::runtime_error("the planner built regions of other planes than those built ahead (the timings would mix)");
      const auto t2 = Clock::now();
      for (;;) {
        const auto ti = Clock::now();
        if (!planner.advance()) break;
        per_iteration.push_back(seconds_since(ti) * 1e6);
      }
      const double t_phase2 = seconds_since(t2);
      faults.push_back(static_cast<double>(minor_faults() - f0));
      object_s.push_back(t_object);
      planner_s.push_back(t_planner);
      phase2_s.push_back(t_phase2);
      total_s.push_back(t_object + t_planner + (sections_s.empty() ? 0.0 : sections_s.back()) + t_phase2);
      const std::uint64_t d = digest(planner);
      if (k == 0) {
        first_digest = d;
        r.digest = d;
        std::snprintf(r.status, sizeof r.status, "%s", to_string(planner.status()).c_str());
        r.configurations = static_cast<long>(planner.history().size());
        r.phase1_configurations = planner.stats().phase1_configurations;
        r.phase2_iterations = planner.stats().phase2_iterations;
        iterations = static_cast<std::size_t>(r.phase2_iterations) + 1;
      } else if (d != first_digest) {
        r.deterministic = false;
      }
    }
    r.object_s = median(object_s);
    r.planner_s = median(planner_s);
    r.phase2_s = median(phase2_s);
    r.total_s = median(total_s);
    r.sections_s = median(sections_s);
    r.object_faults = median(object_faults);
    r.faults = median(faults);
    r.iterations_per_s = r.phase2_s > 0 ? static_cast<double>(r.phase2_iterations) / r.phase2_s : 0.0;
    std::sort(per_iteration.begin(), per_iteration.end());
    r.p50_us = percentile(per_iteration, 0.50);
    r.p90_us = percentile(per_iteration, 0.90);
    r.p99_us = percentile(per_iteration, 0.99);
    r.max_us = per_iteration.empty() ? 0.0 : per_iteration.back();
    r.ok = true;
  } catch (const std::exception& e) {
    std::snprintf(r.error, sizeof r.error, "%s", e.what());
  }
  r.max_rss_mib = max_rss_mib();
  return r;
}

/// Runs a scenario in a child process (its own peak memory); falls back to in-process on error.
Result run_isolated(const Scenario& sc, const std::string& skin, int repeats) {
  int fd[2];
  if (pipe(fd) != 0) return run(sc, skin, repeats);
  const pid_t pid = fork();
  if (pid < 0) {
    close(fd[0]);
    close(fd[1]);
    return run(sc, skin, repeats);
  }
  if (pid == 0) {
    close(fd[0]);
    const Result r = run(sc, skin, repeats);
    const char* p = reinterpret_cast<const char*>(&r);
    std::size_t left = sizeof r;
    while (left > 0) {
      const ssize_t w = write(fd[1], p, left);
      if (w <= 0) _exit(2);
      p += w;
      left -= static_cast<std::size_t>(w);
    }
    close(fd[1]);
    _exit(0);
  }
  close(fd[1]);
  Result r;
  char* p = reinterpret_cast<char*>(&r);
  std::size_t got = 0;
  while (got < sizeof r) {
    const ssize_t n = read(fd[0], p + got, sizeof r - got);
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  close(fd[0]);
  int wstatus = 0;
  waitpid(pid, &wstatus, 0);
  if (got != sizeof r) {
    r = Result();
    std::snprintf(r.name, sizeof r.name, "%s", sc.name.c_str());
    std::snprintf(r.skin, sizeof r.skin, "%s", skin.c_str());
    std::snprintf(r.error, sizeof r.error, "the benchmark process died (wait status %d)", wstatus);
  }
  return r;
}

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\', o += c;
    else if (static_cast<unsigned char>(c) < 0x20) o += ' ';
    else o += c;
  }
  return o + "\"";
}

std::string load_average() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  if (!(f >> a >> b >> c)) return "unknown";
  return a + " " + b + " " + c;
}

/// The usage, to `out`: stdout for --help, stderr after an error.
void usage(const std::vector<Scenario>& all, FILE* out) {
  std::fprintf(out,
               "usage: hugger_bench [--scenario NAME]... [--skin mesh|section|both] [--repeat R] [--json] [--list]\n"
               "                    [--no-fork] [--allow-debug]\n"
               "       hugger_bench --dump-obj SCENARIO FILE   (write the scenario's object as OBJ)\n"
               "scenarios:");
  for (const auto& s : all) std::fprintf(out, " %s", s.name.c_str());
  std::fprintf(out, "\n");
}

/// A positive count of repeats, or 0 for anything else (not a whole number, or beyond 1e6).
int parse_repeats(const char* text) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || errno != 0 || v < 1 || v > 1000000) return 0;
  return static_cast<int>(v);
}

}  // namespace

int main(int argc, char** argv) {
  const auto all = scenarios();
  auto find_scenario = [&](const std::string& name) -> const Scenario* {  // nullptr: none of that name
    auto it = std::find_if(all.begin(), all.end(), [&](const Scenario& s) { return s.name == name; });
    return it == all.end() ? nullptr : &*it;
  };
  std::vector<std::string> chosen;
  int repeats = 5;
  bool json = false, fork_each = true, allow_debug = false, list = false;
  std::vector<std::string> skins = {"mesh", "section"};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--scenario" && has_value) chosen.push_back(argv[++i]);
    else if (a == "--repeat" && has_value) {
      repeats = parse_repeats(argv[++i]);
      if (repeats == 0) {
        std::fprintf(stderr, "hugger_bench: --repeat must be a whole number from 1 to 1000000, got '%s'\n", argv[i]);
        return 2;
      }
    }
    else if (a == "--json") json = true;
    else if (a == "--skin" && has_value) {
      const std::string k = argv[++i];
      if (k == "both") skins = {"mesh", "section"};
      else if (k == "mesh" || k == "section") skins = {k};
      else {
        std::fprintf(stderr, "hugger_bench: --skin must be mesh, section or both, got '%s'\n", k.c_str());
        return 2;
      }
    }
    else if (a == "--no-fork") fork_each = false;
    else if (a == "--allow-debug") allow_debug = true;
    else if (a == "--dump-obj" && i + 2 < argc) {
      // The scenario's object as Wavefront OBJ, every coordinate to 17 significant digits
      // (round-trips exactly), to compare with the Python built-in (hugger.objects.curvy()).
      const std::string name = argv[++i], path = argv[++i];
      const Scenario* sc = find_scenario(name);
      if (sc == nullptr) {
        std::fprintf(stderr, "hugger_bench: unknown scenario '%s'\n", name.c_str());
        return 2;
      }
      const Mesh m = sc->mesh();
      FILE* f = std::fopen(path.c_str(), "w");
      if (!f) {
        std::fprintf(stderr, "hugger_bench: cannot write %s\n", path.c_str());
        return 2;
      }
      for (Eigen::Index v = 0; v < m.vertices.rows(); ++v)
        std::fprintf(f, "v %.17g %.17g %.17g\n", m.vertices(v, 0), m.vertices(v, 1), m.vertices(v, 2));
      for (Eigen::Index t = 0; t < m.faces.rows(); ++t)
        std::fprintf(f, "f %lld %lld %lld\n", static_cast<long long>(m.faces(t, 0) + 1),
                     static_cast<long long>(m.faces(t, 1) + 1), static_cast<long long>(m.faces(t, 2) + 1));
      const bool written = !std::ferror(f);
      if (std::fclose(f) != 0 || !written) {
        std::fprintf(stderr, "hugger_bench: cannot write %s\n", path.c_str());
        return 2;
      }
      return 0;
    }
    else if (a == "--list") list = true;
    else if (a == "--help" || a == "-h") {
      usage(all, stdout);
      return 0;
    } else {
      const bool known = a == "--scenario" || a == "--repeat" || a == "--skin" || a == "--dump-obj";
      std::fprintf(stderr, known ? "hugger_bench: %s needs %s\n" : "hugger_bench: unknown option '%s'%s\n", a.c_str(),
                   known ? (a == "--dump-obj" ? "a scenario and a file" : "a value") : "");
      usage(all, stderr);
      return 2;
    }
  }
  if (list) {  // the scenarios, as a table or (--json) as a JSON list
    if (!json)
      for (const auto& s : all) std::printf("%-12s %-26s %s\n", s.name.c_str(), s.object.c_str(), s.hand.c_str());
    else
      for (std::size_t k = 0; k < all.size(); ++k)
        std::printf("%s{\"name\": %s, \"object\": %s, \"hand\": %s}%s\n", k == 0 ? "[" : " ",
                    json_string(all[k].name).c_str(), json_string(all[k].object).c_str(),
                    json_string(all[k].hand).c_str(), k + 1 == all.size() ? "]" : ",");
    return 0;
  }
  if (!kReleaseBuild) {
    std::fprintf(stderr,
                 "\n*** hugger_bench was built WITHOUT NDEBUG (a debug build): its timings mean nothing. ***\n"
                 "*** Configure with -DCMAKE_BUILD_TYPE=Release, or run with --allow-debug anyway.     ***\n\n");
    if (!allow_debug) return 3;
  }
  std::vector<const Scenario*> todo;
  for (const auto& name : chosen) {
    const Scenario* sc = find_scenario(name);
    if (sc == nullptr) {
      std::fprintf(stderr, "hugger_bench: unknown scenario '%s'\n", name.c_str());
      usage(all, stderr);
      return 2;
    }
    todo.push_back(sc);
  }
  if (todo.empty())
    for (const auto& s : all) todo.push_back(&s);

  FILE* table = json ? stderr : stdout;
  std::fprintf(table, "hugger_bench: %s build, %d repeat(s), medians; %u hardware threads; load average %s\n",
               kReleaseBuild ? "Release" : "DEBUG", repeats, std::thread::hardware_concurrency(),
               load_average().c_str());
  std::fprintf(table, "%-11s %-7s %8s %5s %6s %6s %8s %8s %8s %8s %8s %9s %7s %7s %7s %7s %7s %7s %-14s\n", "scenario", "skin",
               "tris", "MxN", "confs", "iters", "obj ms", "plan1 ms", "sect ms", "phase2ms", "total ms", "iter/s",
               "p50 us", "p90 us", "p99 us", "max us", "RSS MiB", "faults", "status");
  std::vector<Result> results;
  for (const Scenario* sc : todo) {
    std::vector<Result> mine;
    for (const std::string& skin : skins) {
      const Result r = fork_each ? run_isolated(*sc, skin, repeats) : run(*sc, skin, repeats);
      results.push_back(r);
      mine.push_back(r);
      if (!r.ok) {
        std::fprintf(table, "%-11s %-7s FAILED: %s\n", r.name, r.skin, r.error);
        continue;
      }
      char mxn[16];
      std::snprintf(mxn, sizeof mxn, "%ldx%ld", r.fingers, r.links);
      std::fprintf(table,
                   "%-11s %-7s %8ld %5s %6ld %6ld %8.2f %8.2f %8.2f %8.2f %8.2f %9.0f %7.1f %7.1f %7.1f %7.1f %7.1f %7.0f %-14s%s\n",
                   r.name, r.skin, r.triangles, mxn, r.configurations, r.phase2_iterations, r.object_s * 1e3,
                   r.planner_s * 1e3, r.sections_s * 1e3, r.phase2_s * 1e3, r.total_s * 1e3, r.iterations_per_s,
                   r.p50_us, r.p90_us, r.p99_us, r.max_us, r.max_rss_mib, r.faults, r.status,
                   r.deterministic ? "" : " NOT DETERMINISTIC");
      std::fflush(table);
    }
    if (mine.size() == 2 && mine[0].ok && mine[1].ok && mine[1].phase2_s > 0 && mine[1].p50_us > 0 && mine[1].total_s > 0)
      std::fprintf(table, "%-11s %-7s  mesh/section: Phase 2 time %.2fx, per-iteration p50 %.2fx, iterations/s %.2fx, "
                          "total %.2fx\n",
                   "", "ratio", mine[0].phase2_s / mine[1].phase2_s, mine[0].p50_us / mine[1].p50_us,
                   mine[1].iterations_per_s / std::max(mine[0].iterations_per_s, 1e-300),
                   mine[0].total_s / mine[1].total_s);
  }
  if (json) {
    std::ostringstream os;
    os.precision(6);
    os << "{\n  \"build\": " << json_string(kReleaseBuild ? "Release" : "Debug") << ",\n  \"repeats\": " << repeats
       << ",\n  \"load_average\": " << json_string(load_average()) << ",\n  \"scenarios\": [";
    for (std::size_t i = 0; i < results.size(); ++i) {
      const Result& r = results[i];
      os << (i ? "," : "") << "\n    {\"name\": " << json_string(r.name) << ", \"skin\": " << json_string(r.skin)
         << ", \"ok\": " << (r.ok ? "true" : "false");
      if (!r.ok) {
        os << ", \"error\": " << json_string(r.error) << "}";
        continue;
      }
      os << ", \"triangles\": " << r.triangles << ", \"fingers\": " << r.fingers << ", \"links\": " << r.links
         << ", \"status\": " << json_string(r.status) << ", \"configurations\": " << r.configurations
         << ", \"phase1_configurations\": " << r.phase1_configurations
         << ", \"phase2_iterations\": " << r.phase2_iterations << ", \"object_setup_s\": " << r.object_s
         << ", \"planner_setup_and_phase1_s\": " << r.planner_s << ", \"sections_s\": " << r.sections_s << ", \"phase2_s\": " << r.phase2_s
         << ", \"total_s\": " << r.total_s << ", \"phase2_iterations_per_s\": " << r.iterations_per_s
         << ", \"iteration_us\": {\"p50\": " << r.p50_us << ", \"p90\": " << r.p90_us << ", \"p99\": " << r.p99_us
         << ", \"max\": " << r.max_us << "}, \"max_rss_mib\": " << r.max_rss_mib
         << ", \"minor_faults\": {\"object\": " << std::llround(r.object_faults)
         << ", \"plan\": " << std::llround(r.faults) << "}"
         << ", \"deterministic\": " << (r.deterministic ? "true" : "false") << ", \"digest\": \""
         << std::hex << r.digest << std::dec << "\"}";
    }
    os << "\n  ]\n}\n";
    std::fputs(os.str().c_str(), stdout);
  }
  const bool all_ok = std::all_of(results.begin(), results.end(), [](const Result& r) { return r.ok && r.deterministic; });
  return all_ok ? 0 : 1;
}
