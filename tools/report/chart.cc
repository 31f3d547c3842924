#include "tools/report/chart.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "tools/io/atomic_file.h"

extern char** environ;

namespace grove::tools {
namespace {

namespace fs = std::filesystem;

constexpr int kMinSizePx = 200;
constexpr int kMaxSizePx = 8192;
// How much of gnuplot's error output goes into a message.
constexpr int kErrorLines = 4;
constexpr size_t kErrorBytes = 300;

// ColorBrewer Dark2: 8 qualitative colours that stay readable on white.
constexpr std::array<const char*, 8> kPalette = {"#1b9e77", "#d95f02", "#7570b3", "#e7298a",
                                                 "#66a61e", "#e6ab02", "#a6761d", "#666666"};

std::string ErrnoText(int err) { return std::generic_category().message(err); }

bool IsValidUtf8(std::string_view s) {
  static constexpr uint32_t kMinCodePoint[] = {0, 0x80, 0x800, 0x10000};
  size_t i = 0;
  while (i < s.size()) {
    unsigned char c = static_cast<unsigned char>(s[i]);
    int n;
    uint32_t cp;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c & 0xE0) == 0xC0) {
      n = 1;
      cp = c & 0x1F;
    } else if ((c & 0xF0) == 0xE0) {
      n = 2;
      cp = c & 0x0F;
    } else if ((c & 0xF8) == 0xF0) {
      n = 3;
      cp = c & 0x07;
    } else {
      return false;
    }
    if (s.size() - i <= static_cast<size_t>(n)) return false;
    for (int k = 1; k <= n; ++k) {
      unsigned char b = static_cast<unsigned char>(s[i + k]);
      if ((b & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (b & 0x3F);
    }
    if (cp < kMinCodePoint[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
    i += n + 1;
  }
  return true;
}

// `text` as a gnuplot double-quoted string. The backquote is escaped too: gnuplot runs `...`
// inside double quotes as a shell command. "\n" stays a line break; CR is dropped and other
// control characters become spaces (gnuplot would end the line or the string there).
std::string Quote(std::string_view text) {
  std::string out = "\"";
  for (char c : text) {
    switch (c) {
      case '\\':
        out += "\\\\";
        break;
      case '"':
        out += "\\\"";
        break;
      case '`':
        out += "\\`";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        break;
      default:
        out += static_cast<unsigned char>(c) < 0x20 || c == '\x7f' ? ' ' : c;
    }
  }
  out += '"';
  return out;
}

// A log axis from the decade at or below `lo` to the decade at or above `hi`. gnuplot's own
// autoscaling takes log10(1000) for a little less than 3 and adds an empty decade below.
std::string DecadeRange(double lo, double hi) {
  int a = static_cast<int>(std::floor(std::log10(lo) + 1e-9));
  int b = static_cast<int>(std::ceil(std::log10(hi) - 1e-9));
  return fmt::format("[1e{}:1e{}]", a, std::max(b, a + 1));
}

std::string Legend(const std::string& label) {
  return label.empty() ? "notitle" : "title " + Quote(label);
}

// Whether gnuplot can place `v` on the axis.
bool Usable(double v, bool log_axis) { return std::isfinite(v) && (!log_axis || v > 0); }

Status CheckText(const std::string& text, std::string_view name) {
  if (IsValidUtf8(text)) return Status::Ok();
  return InvalidArgumentError(fmt::format("{} {} is not valid UTF-8", name, QuoteForMessage(text)));
}

Status CheckLengths(std::string_view kind, size_t i, const std::string& label, size_t x_size,
                    size_t other_size, std::string_view other) {
  if (x_size == other_size) return Status::Ok();
  return InvalidArgumentError(fmt::format("{}[{}] {}: x has {} values, {} has {}", kind, i,
                                          QuoteForMessage(label), x_size, other, other_size));
}

Status Validate(const Chart& chart, const ChartOptions& options, const std::string& png_path) {
  if (png_path.empty()) return InvalidArgumentError("chart PNG path is empty");
  if (options.width_px < kMinSizePx || options.width_px > kMaxSizePx ||
      options.height_px < kMinSizePx || options.height_px > kMaxSizePx) {
    return InvalidArgumentError(fmt::format("chart size {} x {} px is outside [{}, {}]",
                                            options.width_px, options.height_px, kMinSizePx,
                                            kMaxSizePx));
  }
  GROVE_RETURN_IF_ERROR(CheckText(chart.title, "title"));
  GROVE_RETURN_IF_ERROR(CheckText(chart.x_label, "x_label"));
  GROVE_RETURN_IF_ERROR(CheckText(chart.y_label, "y_label"));
  for (size_t i = 0; i < chart.series.size(); ++i) {
    const ChartSeries& s = chart.series[i];
    GROVE_RETURN_IF_ERROR(CheckText(s.label, fmt::format("series[{}].label", i)));
    GROVE_RETURN_IF_ERROR(CheckLengths("series", i, s.label, s.x.size(), s.y.size(), "y"));
  }
  for (size_t i = 0; i < chart.bands.size(); ++i) {
    const ChartBand& b = chart.bands[i];
    GROVE_RETURN_IF_ERROR(CheckText(b.label, fmt::format("bands[{}].label", i)));
    GROVE_RETURN_IF_ERROR(CheckLengths("bands", i, b.label, b.x.size(), b.y_low.size(), "y_low"));
    GROVE_RETURN_IF_ERROR(CheckLengths("bands", i, b.label, b.x.size(), b.y_high.size(), "y_high"));
  }
  for (size_t i = 0; i < chart.boxes.size(); ++i) {
    GROVE_RETURN_IF_ERROR(CheckText(chart.boxes[i].label, fmt::format("boxes[{}].label", i)));
  }
  return Status::Ok();
}

// An output's directory must exist before gnuplot runs, so that a bad path costs nothing and
// leaves nothing behind.
Status CheckOutputDirectory(const std::string& path) {
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  fs::file_status st = fs::status(dir, ec);
  if (!fs::exists(st)) {
    return IoError(fmt::format("cannot write {}: directory {} does not exist", path, dir.string()));
  }
  if (!fs::is_directory(st)) {
    return IoError(fmt::format("cannot write {}: {} is not a directory", path, dir.string()));
  }
  return Status::Ok();
}

size_t LineType(size_t i) { return i % kPalette.size() + 1; }

// The inline datablocks and the plot elements of a chart, and the range of its usable values
// on each axis.
struct PlotData {
  std::string data;
  std::vector<std::string> elements;
  bool any_data = false;
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;

  void AddBand(size_t i, const ChartBand& b, bool log_x, bool log_y) {
    std::string rows;
    bool usable = false;
    for (size_t k = 0; k < b.x.size(); ++k) {
      if (Usable(b.x[k], log_x) && Usable(b.y_low[k], log_y) && Usable(b.y_high[k], log_y)) {
        rows += fmt::format("{} {} {}\n", b.x[k], b.y_low[k], b.y_high[k]);
        usable = true;
        min_x = std::min(min_x, b.x[k]);
        max_x = std::max(max_x, b.x[k]);
        min_y = std::min({min_y, b.y_low[k], b.y_high[k]});
        max_y = std::max({max_y, b.y_low[k], b.y_high[k]});
      } else {
        rows += "NaN NaN NaN\n";  // undefined: gnuplot cuts the area here
      }
    }
    std::string look = fmt::format("with filledcurves lt {} fs transparent solid 0.25 noborder {}",
                                   LineType(i), Legend(b.label));
    if (usable) {
      data += fmt::format("$band{} << EOD\n{}EOD\n", i, rows);
      elements.push_back(fmt::format("$band{} using 1:2:3 {}", i, look));
    } else if (!b.label.empty()) {
      elements.push_back("keyentry " + look);  // a legend entry without data
    }
    any_data |= usable;
  }

  void AddBox(size_t i, const ChartBox& box, bool log_y) {
    std::string rows;
    for (double v : box.values) {
      if (!Usable(v, log_y)) continue;
      rows += fmt::format("{}\n", v);
      min_y = std::min(min_y, v);
      max_y = std::max(max_y, v);
    }
    if (rows.empty()) return;  // the category keeps its place on the axis
    data += fmt::format("$box{} << EOD\n{}EOD\n", i, rows);
    elements.push_back(fmt::format(
        "$box{} using ({}):1:(0.5) with boxplot lt {} fs transparent solid 0.3 border notitle", i,
        i + 1, LineType(i)));
    any_data = true;
  }

  void AddSeries(size_t i, const ChartSeries& s, bool log_x, bool log_y) {
    std::string rows;
    bool usable = false;
    for (size_t k = 0; k < s.x.size(); ++k) {
      if (Usable(s.x[k], log_x) && Usable(s.y[k], log_y)) {
        rows += fmt::format("{} {}\n", s.x[k], s.y[k]);
        usable = true;
        min_x = std::min(min_x, s.x[k]);
        max_x = std::max(max_x, s.x[k]);
        min_y = std::min(min_y, s.y[k]);
        max_y = std::max(max_y, s.y[k]);
      } else {
        rows += "NaN NaN\n";  // undefined: gnuplot breaks the line here
      }
    }
    std::string look =
        fmt::format("with {} lt {} {}", SeriesStyle(s.style), LineType(i), Legend(s.label));
    if (usable) {
      data += fmt::format("$series{} << EOD\n{}EOD\n", i, rows);
      elements.push_back(fmt::format("$series{} using 1:2 {}", i, look));
    } else if (!s.label.empty()) {
      elements.push_back("keyentry " + look);
    }
    any_data |= usable;
  }

  static const char* SeriesStyle(ChartStyle style) {
    switch (style) {
      case ChartStyle::kLine:
        return "lines";
      case ChartStyle::kLinePoints:
        return "linespoints";
      case ChartStyle::kPoints:
        return "points";
      case ChartStyle::kDashed:
        return "lines dt 2";
    }
    return "lines";
  }
};

// The settings after the data: title, labels, log axes, grid, key, line types and the boxes'
// tics. Sizes are tuned for 1200 x 800 and scale with `scale`.
std::string Settings(const Chart& chart, const PlotData& p, double scale, int font_pt) {
  std::string s = fmt::format("set title {} font \",{}\"\n", Quote(chart.title), font_pt + 2);
  s += fmt::format("set xlabel {}\nset ylabel {}\n", Quote(chart.x_label), Quote(chart.y_label));
  // Log axes span whole decades; from 1 up they read better as 1, 10, 100, 1k, 1M than with
  // gnuplot's 1e+06.
  if (chart.log_x) {
    s += "set logscale x 10\n";
    if (p.min_x >= 1) s += "set format x \"%.0s%c\"\n";
    if (p.min_x <= p.max_x && chart.boxes.empty()) {
      s += fmt::format("set xrange {}\n", DecadeRange(p.min_x, p.max_x));
    }
  }
  if (chart.log_y) {
    s += "set logscale y 10\n";
    if (p.min_y >= 1) s += "set format y \"%.0s%c\"\n";
    if (p.min_y <= p.max_y) s += fmt::format("set yrange {}\n", DecadeRange(p.min_y, p.max_y));
  }
  if (chart.integer_x && !chart.log_x && chart.boxes.empty() && p.min_x <= p.max_x) {
    s += fmt::format("set xtics 1\nset mxtics 1\nset format x \"%.0f\"\nset xrange [{}:{}]\n",
                     std::floor(p.min_x) - 0.5, std::ceil(p.max_x) + 0.5);
  }
  if (chart.y_from_zero && !chart.log_y) s += "set yrange [0:*]\n";
  s += "set border 3 lc rgb \"#404040\"\nset tics nomirror\n";
  s += fmt::format(
      "set grid {}ytics mytics lt 1 lc rgb \"#e4e4e4\" lw 1, lt 1 lc rgb \"#f2f2f2\" lw 1\n",
      chart.boxes.empty() ? "xtics mxtics " : "");
  s += "set key outside right top vertical Left reverse noautotitle\n";
  s += "set style boxplot outliers pointtype 7\n";
  for (size_t i = 0; i < kPalette.size(); ++i) {
    s += fmt::format("set linetype {} lc rgb \"{}\" lw 1.5 pt 7 ps {:.2f}\n", i + 1, kPalette[i],
                     std::max(0.5, 0.9 * scale));
  }
  if (!chart.boxes.empty()) {
    std::string tics;
    for (size_t i = 0; i < chart.boxes.size(); ++i) {
      tics += fmt::format("{}{} {}", i > 0 ? ", " : "", Quote(chart.boxes[i].label), i + 1);
    }
    s += fmt::format("set xtics ({})\nset xrange [0.5:{}.5]\n", tics, chart.boxes.size());
  }
  return s;
}

// The gnuplot script: data as inline datablocks, then the settings, then one plot per terminal.
std::string Script(const Chart& chart, const ChartOptions& options, const std::string& png_path,
                   const std::string& svg_path) {
  PlotData p;
  // Bands first, so that everything else is drawn over them.
  for (size_t i = 0; i < chart.bands.size(); ++i) {
    p.AddBand(i, chart.bands[i], chart.log_x, chart.log_y);
  }
  for (size_t i = 0; i < chart.boxes.size(); ++i) p.AddBox(i, chart.boxes[i], chart.log_y);
  for (size_t i = 0; i < chart.series.size(); ++i) {
    p.AddSeries(i, chart.series[i], chart.log_x, chart.log_y);
  }

  // Sizes are tuned for 1200 x 800 and scale with the smaller ratio.
  const double scale = std::min(options.width_px / 1200.0, options.height_px / 800.0);
  const int font_pt = std::max(8, static_cast<int>(std::lround(14 * scale)));
  const double line_width = std::max(1.0, 1.5 * scale);
  const std::string terminal_options =
      fmt::format("noenhanced size {},{} font \"sans,{}\" linewidth {:.2f} background \"#ffffff\"",
                  options.width_px, options.height_px, font_pt, line_width);

  std::string s = "set encoding utf8\n" + p.data + Settings(chart, p, scale, font_pt);
  if (!p.any_data) {
    // gnuplot cannot autoscale nothing: fixed unit ranges and one undefined function.
    if (chart.boxes.empty()) s += chart.log_x ? "set xrange [1:10]\n" : "set xrange [0:1]\n";
    s += chart.log_y ? "set yrange [1:10]\n" : "set yrange [0:1]\n";
    p.elements.insert(p.elements.begin(), "NaN notitle");
  }
  std::string plot = "plot ";
  for (size_t i = 0; i < p.elements.size(); ++i) {
    plot += (i > 0 ? ", \\\n     " : "") + p.elements[i];
  }
  s += fmt::format("set terminal pngcairo {}\nset output {}\n{}\n", terminal_options,
                   Quote(png_path), plot);
  if (!svg_path.empty()) {
    s += fmt::format("set terminal svg {}\nset output {}\nreplot\n", terminal_options,
                     Quote(svg_path));
  }
  s += "unset output\n";
  return s;
}

// Up to kErrorLines non-blank lines of gnuplot's error output, quoted and bounded. The lines
// holding only the "^" that points into the echoed command are left out.
std::string ErrorExcerpt(const std::string& log) {
  std::istringstream in(log);
  std::string line, out;
  int lines = 0;
  while (lines < kErrorLines && std::getline(in, line)) {
    size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line.compare(first, std::string::npos, "^") == 0) continue;
    size_t last = line.find_last_not_of(" \t\r");
    if (!out.empty()) out += " | ";
    out += line.substr(first, last - first + 1);
    ++lines;
  }
  return out.empty() ? "no error output" : QuoteForMessage(out, kErrorBytes);
}

StatusOr<std::string> ReadWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return IoError(fmt::format("cannot open {}", path));
  std::string contents((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return IoError(fmt::format("cannot read {}", path));
  return contents;
}

// Starts `program args...` with stdin and stdout on `null_fd` and stderr on `stderr_fd`, and no
// signal blocked (a caller that blocks SIGINT or SIGTERM in this thread must not pass that on).
// Returns 0 or an errno value; ENOENT means that the program was not found.
int Spawn(const std::string& program, const std::vector<std::string>& args, int null_fd,
          int stderr_fd, pid_t* pid) {
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(program.c_str()));
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  int rc = posix_spawn_file_actions_init(&actions);
  if (rc != 0) return rc;
  posix_spawnattr_t attr;
  rc = posix_spawnattr_init(&attr);
  if (rc == 0) {
    sigset_t none;
    sigemptyset(&none);
    rc = posix_spawn_file_actions_adddup2(&actions, null_fd, STDIN_FILENO);
    if (rc == 0) rc = posix_spawn_file_actions_adddup2(&actions, null_fd, STDOUT_FILENO);
    if (rc == 0) rc = posix_spawn_file_actions_adddup2(&actions, stderr_fd, STDERR_FILENO);
    if (rc == 0) rc = posix_spawnattr_setsigmask(&attr, &none);
    if (rc == 0) rc = posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK);
    if (rc == 0) rc = posix_spawnp(pid, program.c_str(), &actions, &attr, argv.data(), environ);
    posix_spawnattr_destroy(&attr);
  }
  posix_spawn_file_actions_destroy(&actions);
  return rc;
}

// Runs gnuplot on `script_path`, its error output going to `log_path`. No pipe connects us to
// gnuplot (its input is a file), so there is no SIGPIPE to meet; waitpid is retried on EINTR.
Status RunGnuplot(const std::string& gnuplot, const std::string& script_path,
                  const std::string& log_path, const std::string& what) {
  // Opened here rather than by the child, so that a failure cannot pass for a missing gnuplot.
  int null_fd = ::open("/dev/null", O_RDWR | O_CLOEXEC);
  if (null_fd < 0) return IoError(fmt::format("cannot open /dev/null: {}", ErrnoText(errno)));
  int log_fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (log_fd < 0) {
    int err = errno;
    ::close(null_fd);
    return IoError(fmt::format("cannot create {}: {}", log_path, ErrnoText(err)));
  }
  pid_t pid = -1;
  // -d: no initialisation files, so that a user's ~/.gnuplot cannot change the chart.
  int rc = Spawn(gnuplot, {"-d", script_path}, null_fd, log_fd, &pid);
  ::close(log_fd);
  ::close(null_fd);
  if (rc == ENOENT) {
    return NotFoundError(
        fmt::format("gnuplot not found ({}), needed to draw {}: install Debian's gnuplot-nox "
                    "(apt-get install gnuplot-nox)",
                    QuoteForMessage(gnuplot, 200), what));
  }
  if (rc != 0) {
    return IoError(
        fmt::format("cannot run gnuplot {}: {}", QuoteForMessage(gnuplot, 200), ErrnoText(rc)));
  }
  int wait_status = 0;
  pid_t waited;
  do {
    waited = ::waitpid(pid, &wait_status, 0);
  } while (waited < 0 && errno == EINTR);
  if (waited < 0) {
    return InternalError(fmt::format("cannot wait for gnuplot: {}", ErrnoText(errno)));
  }
  if (WIFEXITED(wait_status) && WEXITSTATUS(wait_status) == 0) return Status::Ok();
  StatusOr<std::string> log = ReadWholeFile(log_path);
  std::string how = WIFEXITED(wait_status)
                        ? fmt::format("exit status {}", WEXITSTATUS(wait_status))
                        : fmt::format("killed by signal {}", WTERMSIG(wait_status));
  return InternalError(fmt::format("gnuplot failed drawing {} ({}): {}", what, how,
                                   log.ok() ? ErrorExcerpt(*log) : log.status().message()));
}

// A private directory, removed with everything in it when this goes out of scope.
class TempDirectory {
 public:
  static StatusOr<TempDirectory> Create() {
    const char* env = std::getenv("TMPDIR");
    std::string base = env != nullptr && *env != '\0' ? env : "/tmp";
    std::string pattern = base + "/grove-chart-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) {
      return IoError(
          fmt::format("cannot create a temporary directory in {}: {}", base, ErrnoText(errno)));
    }
    return TempDirectory(std::move(pattern));
  }
  TempDirectory(TempDirectory&& other) noexcept : path_(std::exchange(other.path_, {})) {}
  TempDirectory& operator=(TempDirectory&&) = delete;
  ~TempDirectory() {
    std::error_code ec;
    if (!path_.empty()) fs::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  explicit TempDirectory(std::string path) : path_(std::move(path)) {}
  std::string path_;
};

// Copies gnuplot's image `from` to `to` with WriteFileAtomically.
Status Publish(const std::string& from, const std::string& to, const std::string& what) {
  StatusOr<std::string> image = ReadWholeFile(from);
  if (!image.ok() || image->empty()) {
    return InternalError(fmt::format("gnuplot wrote no image for {}", what));
  }
  return WriteFileAtomically(to, *image);
}

Status WriteChartOrThrow(const Chart& chart, const std::string& png_path,
                         const std::string& svg_path, const ChartOptions& options) {
  GROVE_RETURN_IF_ERROR(Validate(chart, options, png_path));
  GROVE_RETURN_IF_ERROR(CheckOutputDirectory(png_path));
  if (!svg_path.empty()) GROVE_RETURN_IF_ERROR(CheckOutputDirectory(svg_path));
  StatusOr<TempDirectory> temp = TempDirectory::Create();
  if (!temp.ok()) return temp.status();
  const std::string dir = temp->path();
  const std::string temp_png = dir + "/chart.png";
  const std::string temp_svg = svg_path.empty() ? "" : dir + "/chart.svg";
  const std::string script_path = dir + "/chart.gp";
  GROVE_RETURN_IF_ERROR(
      WriteFileAtomically(script_path, Script(chart, options, temp_png, temp_svg)));
  GROVE_RETURN_IF_ERROR(RunGnuplot(options.gnuplot, script_path, dir + "/stderr.txt", png_path));
  GROVE_RETURN_IF_ERROR(Publish(temp_png, png_path, png_path));
  if (!svg_path.empty()) GROVE_RETURN_IF_ERROR(Publish(temp_svg, svg_path, svg_path));
  return Status::Ok();
}

}  // namespace

std::string ChartScript(const Chart& chart, const ChartOptions& options,
                        const std::string& png_path, const std::string& svg_path) {
  return Script(chart, options, png_path, svg_path);
}

Status WriteChart(const Chart& chart, const std::string& png_path, const std::string& svg_path,
                  const ChartOptions& options) {
  try {
    return WriteChartOrThrow(chart, png_path, svg_path, options);
  } catch (const std::exception& e) {  // std::bad_alloc, mostly
    return InternalError(fmt::format("drawing {}: {}", png_path, e.what()));
  }
}

}  // namespace grove::tools
