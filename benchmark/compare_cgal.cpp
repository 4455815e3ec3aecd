// SPDX-License-Identifier: GPL-3.0-or-later
// compare_cgal: quality and speed of our orientation program against CGAL::mst_orient_normals.
//
// For each mesh and each noise level, generates a cloud in process (Mesh_sampler.h), runs
// both programs as child processes (wall-clock time, peak RSS from wait4), counts the wrong
// normals of each against the ground truth and prints a Markdown table. See README.md.
#include "Benchmark_options.h"
#include "Mesh_sampler.h"
#include "Xyz_io.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#ifndef NORMAL_ORIENTATION_BENCHMARK_OURS
#define NORMAL_ORIENTATION_BENCHMARK_OURS "examples/orient_normals"
#endif
#ifndef NORMAL_ORIENTATION_BENCHMARK_PEER
#define NORMAL_ORIENTATION_BENCHMARK_PEER "benchmark/cgal_mst_orient"
#endif
#ifndef NORMAL_ORIENTATION_BENCHMARK_MESH_DIR
#define NORMAL_ORIENTATION_BENCHMARK_MESH_DIR "/work/shared/data/meshes"
#endif

namespace {

namespace fs = std::filesystem;
using namespace Normal_orientation::benchmark;

// ---------------------------------------------------------------------------------------
// Options
// ---------------------------------------------------------------------------------------

/// Command-line options of compare_cgal.
struct Options : Cloud_options
{
  Options() { noises = {0.0, 0.005}; }
  /// Our orientation program.
  std::string ours = NORMAL_ORIENTATION_BENCHMARK_OURS;
  /// The peer program wrapping CGAL::mst_orient_normals.
  std::string peer = NORMAL_ORIENTATION_BENCHMARK_PEER;
  /// Extra arguments of ours (placed after --quiet, before IN OUT).
  std::vector<std::string> ours_arguments;
  /// Extra arguments of the peer (placed before IN OUT).
  std::vector<std::string> peer_arguments;
  /// Directory where clouds and outputs are kept (empty: a temporary directory, removed).
  std::string keep_directory;
  /// Runs of each program per cloud; the reported time is the minimum.
  unsigned int repeat = 1;
};

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(
    out,
    "usage: compare_cgal [options]\n"
    "  --meshes DIR_OR_FILES...  meshes (.off files, or directories whose *.off are used);\n"
    "                            default: " NORMAL_ORIENTATION_BENCHMARK_MESH_DIR "/*.off\n"
    "  --points N                points per cloud (default 30000)\n"
    "  --noise a,b,...           noise levels, x bbox diagonal (default 0,0.005)\n"
    "  --seed S                  seed of the clouds (default 1; same as make_cloud --seed)\n"
    "  --ours PATH               our program (default " NORMAL_ORIENTATION_BENCHMARK_OURS ")\n"
    "  --peer PATH               CGAL peer (default " NORMAL_ORIENTATION_BENCHMARK_PEER ")\n"
    "  --ours-args \"...\"         extra arguments for ours, e.g. \"--k 12 --criterion xie\"\n"
    "  --peer-args \"...\"         extra arguments for the peer, e.g. \"--k 12\"\n"
    "  --keep DIR                keep clouds, outputs and logs in DIR (default: temp dir, removed)\n"
    "  --repeat R                run each program R times per cloud, report the minimum time and\n"
    "                            the largest peak memory (default 1)\n"
    "Runs '<ours> --quiet [ours-args] IN OUT' and '<peer> [peer-args] IN OUT' on every cloud and\n"
    "prints a Markdown table. Exit status: 0 if every run succeeded, 1 if a run failed, 2 on\n"
    "usage errors.\n");
}

/// Splits `text` at whitespace.
std::vector<std::string> split_words(const std::string& text)
{
  std::istringstream stream(text);
  std::vector<std::string> words;
  std::string word;
  while(stream >> word)
    words.push_back(word);
  return words;
}


/// Parses the command line into `options`; returns false (after printing why) on an error.
bool parse_options(int argc, char** argv, Options& options, bool& help)
{
  help = false;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if(arg == "-h" || arg == "--help")
    {
      help = true;
      return true;
    }
    else if(const int parsed = parse_cloud_option(argc, argv, i, options, "compare_cgal"))
    {
      if(parsed < 0)
        return false;
    }
    else if(arg == "--ours" && has_value)
      options.ours = argv[++i];
    else if(arg == "--peer" && has_value)
      options.peer = argv[++i];
    else if(arg == "--ours-args" && has_value)
      options.ours_arguments = split_words(argv[++i]);
    else if(arg == "--peer-args" && has_value)
      options.peer_arguments = split_words(argv[++i]);
    else if(arg == "--keep" && has_value)
      options.keep_directory = argv[++i];
    else if(arg == "--repeat" && has_value)
    {
      char* stop = nullptr;
      const char* text = argv[++i];
      const unsigned long value = std::strtoul(text, &stop, 10);
      if(text[0] == '-' || stop == text || *stop != '\0' || value == 0 || value > 1000)
      {
        std::fprintf(stderr, "compare_cgal: invalid --repeat '%s' (1..1000)\n", text);
        return false;
      }
      options.repeat = static_cast<unsigned int>(value);
    }
    else
    {
      std::fprintf(stderr, "compare_cgal: unknown or incomplete option '%s'\n", arg.c_str());
      return false;
    }
  }
  return true;
}


// ---------------------------------------------------------------------------------------
// Child processes
// ---------------------------------------------------------------------------------------

/// What the spawner reports about one child process.
struct Child_result
{
  /// 0 if the program was started, otherwise the errno of fork/open/execv.
  int start_errno = 0;
  /// True if the child exited normally (then `exit_code` is valid), false if killed.
  bool exited = false;
  /// Exit status of the child.
  int exit_code = -1;
  /// Signal that killed the child (when `!exited`).
  int signal_number = 0;
  /// Wall-clock seconds from fork to the end of wait4.
  double seconds = 0.0;
  /// Peak resident set size of the child (ru_maxrss), in MiB.
  double peak_mb = 0.0;
};

/// Moves exactly `size` bytes between `fd` and `data` with `transfer` (::read or ::write),
/// retrying on EINTR and short transfers; returns false on end of file or error.
template <typename Buffer, typename Transfer>
bool transfer_all(int fd, Buffer* data, std::size_t size, Transfer transfer)
{
  auto* p = reinterpret_cast<std::conditional_t<std::is_const<Buffer>::value, const char, char>*>(data);
  while(size > 0)
  {
    const ssize_t n = transfer(fd, p, size);
    if(n < 0 && errno == EINTR)
      continue;
    if(n <= 0)
      return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

/// Writes `size` bytes to `fd`, retrying on EINTR and short writes; returns false on error.
bool write_all(int fd, const void* data, std::size_t size) { return transfer_all(fd, data, size, ::write); }

/// Reads exactly `size` bytes from `fd`, retrying on EINTR; returns false on EOF or error.
bool read_all(int fd, void* data, std::size_t size) { return transfer_all(fd, data, size, ::read); }

/// Sends a length-prefixed string over `fd`.
bool write_string(int fd, const std::string& s)
{
  const std::uint32_t size = static_cast<std::uint32_t>(s.size());
  return write_all(fd, &size, sizeof(size)) && write_all(fd, s.data(), s.size());
}

/// Receives a length-prefixed string from `fd`.
bool read_string(int fd, std::string& s)
{
  std::uint32_t size = 0;
  if(!read_all(fd, &size, sizeof(size)))
    return false;
  s.assign(size, '\0');
  return size == 0 || read_all(fd, &s[0], size);
}

/**
 * \brief Runs child processes (fork + execv, wait4) from a small helper process.
 *
 * On Linux, `ru_maxrss` of a child that was forked and then exec'd includes the memory it
 * inherited at fork time: a parent holding a 500 MB cloud makes `/bin/true` report 500 MB.
 * The generated clouds live in this process, so the children are started by a "spawner"
 * forked at start-up, while this process is still small, and which never allocates much.
 * The spawner measures wall-clock time and peak RSS and sends them back over a pipe.
 */
class Child_spawner
{
public:
  /// Forks the spawner. Call before allocating large data and before starting threads.
  Child_spawner()
  {
    int request[2], response[2];
    if(::pipe2(request, O_CLOEXEC) != 0 || ::pipe2(response, O_CLOEXEC) != 0)
      throw std::runtime_error(std::string("pipe2: ") + std::strerror(errno));
    std::fflush(stdout);
    std::fflush(stderr);
    m_pid = ::fork();
    if(m_pid < 0)
      throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    if(m_pid == 0)
    {
      ::close(request[1]);
      ::close(response[0]);
      serve(request[0], response[1]);
      ::_exit(0);
    }
    ::close(request[0]);
    ::close(response[1]);
    m_request_fd = request[1];
    m_response_fd = response[0];
  }

  /// Stops the spawner (closing its request pipe makes it exit) and reaps it.
  ~Child_spawner()
  {
    ::close(m_request_fd);
    ::close(m_response_fd);
    int status = 0;
    while(::waitpid(m_pid, &status, 0) < 0 && errno == EINTR)
    {
    }
  }

  Child_spawner(const Child_spawner&) = delete;
  Child_spawner& operator=(const Child_spawner&) = delete;

  /**
   * \brief Runs `arguments[0]` with `arguments`, stdin from /dev/null, stdout and stderr
   * redirected to the given files, and waits for it.
   * \throws std::runtime_error if the spawner is gone.
   */
  Child_result run(const std::vector<std::string>& arguments, const std::string& stdout_path,
                   const std::string& stderr_path)
  {
    const std::uint32_t count = static_cast<std::uint32_t>(arguments.size());
    bool ok = write_all(m_request_fd, &count, sizeof(count));
    for(const std::string& a : arguments)
      ok = ok && write_string(m_request_fd, a);
    ok = ok && write_string(m_request_fd, stdout_path) && write_string(m_request_fd, stderr_path);
    Child_result result;
    if(!ok || !read_all(m_response_fd, &result, sizeof(result)))
      throw std::runtime_error("the process spawner died");
    return result;
  }

private:
  /// The spawner's loop: one request (argv, stdout path, stderr path) -> one Child_result.
  [[noreturn]] static void serve(int request_fd, int response_fd)
  {
    for(;;)
    {
      std::uint32_t count = 0;
      if(!read_all(request_fd, &count, sizeof(count)))
        ::_exit(0); // the parent closed the pipe: done
      std::vector<std::string> arguments(count);
      std::string stdout_path, stderr_path;
      bool ok = true;
      for(std::string& a : arguments)
        ok = ok && read_string(request_fd, a);
      ok = ok && read_string(request_fd, stdout_path) && read_string(request_fd, stderr_path);
      if(!ok || arguments.empty())
        ::_exit(1);
      const Child_result result = run_one(arguments, stdout_path, stderr_path);
      if(!write_all(response_fd, &result, sizeof(result)))
        ::_exit(1);
    }
  }

  /// Forks, execs and waits for one child (runs inside the spawner).
  static Child_result run_one(const std::vector<std::string>& arguments, const std::string& stdout_path,
                              const std::string& stderr_path)
  {
    Child_result result;
    std::vector<char*> argv;
    for(const std::string& a : arguments)
      argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);

    // The child reports a failure before or at execv through this close-on-exec pipe.
    int report[2];
    if(::pipe2(report, O_CLOEXEC) != 0)
    {
      result.start_errno = errno;
      return result;
    }
    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = ::fork();
    if(pid < 0)
    {
      result.start_errno = errno;
      ::close(report[0]);
      ::close(report[1]);
      return result;
    }
    if(pid == 0)
    {
      ::close(report[0]);
      const int in = ::open("/dev/null", O_RDONLY);
      const int out = ::open(stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = ::open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if(in < 0 || out < 0 || err < 0 || ::dup2(in, 0) < 0 || ::dup2(out, 1) < 0 || ::dup2(err, 2) < 0)
      {
        const int e = errno;
        write_all(report[1], &e, sizeof(e));
        ::_exit(127);
      }
      ::close(in);
      ::close(out);
      ::close(err);
      ::execv(argv[0], argv.data());
      const int e = errno;
      write_all(report[1], &e, sizeof(e));
      ::_exit(127);
    }
    ::close(report[1]);
    int child_errno = 0;
    if(read_all(report[0], &child_errno, sizeof(child_errno)))
      result.start_errno = child_errno;
    ::close(report[0]);

    int status = 0;
    struct rusage usage;
    std::memset(&usage, 0, sizeof(usage));
    while(::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR)
    {
    }
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0; // ru_maxrss is in KiB on Linux
    if(WIFEXITED(status))
    {
      result.exited = true;
      result.exit_code = WEXITSTATUS(status);
    }
    else if(WIFSIGNALED(status))
      result.signal_number = WTERMSIG(status);
    return result;
  }

  pid_t m_pid = -1;
  int m_request_fd = -1;
  int m_response_fd = -1;
};

// ---------------------------------------------------------------------------------------
// Evaluation
// ---------------------------------------------------------------------------------------

/// Outcome of one program on one cloud.
struct Side_result
{
  /// Process measurements.
  Child_result child;
  /// True if the program succeeded and its output is usable.
  bool ok = false;
  /// Why the run failed (when `!ok`).
  std::string failure;
  /// Number of normals with dot(n_out, n_true) <= 0 (or not a number).
  std::size_t wrong = 0;
  /// True if repeated runs gave different numbers of wrong normals (`wrong` is the first).
  bool unstable = false;
};

/// Folds the repeated run `run` into `total`: minimum time, largest peak memory, any
/// failure wins, and a different wrong count marks the result unstable.
void merge_repeat(Side_result& total, const Side_result& run)
{
  if(!total.ok)
    return;
  if(!run.ok)
  {
    total = run;
    return;
  }
  total.child.seconds = (std::min)(total.child.seconds, run.child.seconds);
  total.child.peak_mb = (std::max)(total.child.peak_mb, run.child.peak_mb);
  if(run.wrong != total.wrong)
    total.unstable = true;
}

/// One row of the table.
struct Row
{
  /// Mesh name (file stem).
  std::string mesh;
  /// Points in the cloud.
  std::size_t points = 0;
  /// Noise level (fraction of the bounding-box diagonal).
  double noise = 0.0;
  /// Result of our program.
  Side_result ours;
  /// Result of the CGAL peer.
  Side_result cgal;
};

/// Returns the last `lines` lines of the file `path` (empty if it cannot be read).
std::string file_tail(const std::string& path, std::size_t lines)
{
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  std::size_t end = text.size();
  while(end > 0 && (text[end - 1] == '\n' || text[end - 1] == '\r'))
    --end;
  std::size_t begin = end;
  std::size_t found = 0;
  while(begin > 0 && found < lines)
  {
    --begin;
    if(text[begin] == '\n')
      ++found;
  }
  if(begin < end && text[begin] == '\n')
    ++begin;
  return text.substr(begin, end - begin);
}

/**
 * \brief Checks a finished run and counts its wrong normals.
 *
 * The output must hold as many points as the cloud, in the same order: each output
 * position must match the input position within `tolerance` on every coordinate.
 * A normal is wrong when `!(dot(n_out, n_true) > 0)`, which includes zero and NaN normals.
 */
Side_result evaluate(const Child_result& child, const std::string& output_path, const Sampled_cloud& cloud,
                     double tolerance)
{
  Side_result side;
  side.child = child;
  if(child.start_errno != 0)
  {
    side.failure = std::string("could not start: ") + std::strerror(child.start_errno);
    return side;
  }
  if(!child.exited)
  {
    side.failure = "killed by signal " + std::to_string(child.signal_number) + " ("
                 + ::strsignal(child.signal_number) + ")";
    return side;
  }
  if(child.exit_code != 0)
  {
    side.failure = "exit status " + std::to_string(child.exit_code);
    return side;
  }
  std::vector<Xyz_row> rows;
  std::string error;
  if(!read_xyz_rows(output_path, rows, error))
  {
    side.failure = "unreadable output: " + error;
    return side;
  }
  if(rows.size() != cloud.points.size())
  {
    side.failure = "output holds " + std::to_string(rows.size()) + " points, expected "
                 + std::to_string(cloud.points.size());
    return side;
  }
  for(std::size_t i = 0; i < rows.size(); ++i)
  {
    const Xyz_row& r = rows[i];
    const Point_3& p = cloud.points[i];
    if(!(std::abs(r[0] - p.x()) <= tolerance && std::abs(r[1] - p.y()) <= tolerance
         && std::abs(r[2] - p.z()) <= tolerance))
    {
      side.failure = "output point " + std::to_string(i) + " is not input point " + std::to_string(i)
                   + " (point order changed?)";
      return side;
    }
    const Vector_3& g = cloud.true_normals[i];
    const double dot = r[3] * g.x() + r[4] * g.y() + r[5] * g.z();
    if(!(dot > 0.0))
      ++side.wrong;
  }
  side.ok = true;
  return side;
}

// ---------------------------------------------------------------------------------------
// Report
// ---------------------------------------------------------------------------------------

/// printf-style formatting into a std::string.
template <typename... Args>
std::string format(const char* pattern, Args... args)
{
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), pattern, args...);
  return buffer;
}

/// Formats a count of wrong normals with its percentage.
std::string format_wrong(std::size_t wrong, std::size_t total)
{
  const double percent = total == 0 ? 0.0 : 100.0 * static_cast<double>(wrong) / static_cast<double>(total);
  return format("%zu (%.3f%%)", wrong, percent);
}

/// Formats a ratio `numerator / denominator` as e.g. "2.31x" ("-" if undefined).
std::string format_ratio(double numerator, double denominator)
{
  if(!(denominator > 0.0) || !(numerator >= 0.0))
    return "-";
  return format("%.2fx", numerator / denominator);
}

/// Prints `table` (first row = header) as a Markdown table with padded columns.
void print_markdown_table(const std::vector<std::vector<std::string>>& table, const std::vector<bool>& right_align)
{
  std::vector<std::size_t> width(table.front().size(), 3);
  for(const std::vector<std::string>& row : table)
    for(std::size_t c = 0; c < row.size(); ++c)
      width[c] = (std::max)(width[c], row[c].size());
  auto print_row = [&](const std::vector<std::string>& row) {
    std::string line = "|";
    for(std::size_t c = 0; c < row.size(); ++c)
    {
      const std::string pad(width[c] - row[c].size(), ' ');
      line += " " + (right_align[c] ? pad + row[c] : row[c] + pad) + " |";
    }
    std::printf("%s\n", line.c_str());
  };
  print_row(table.front());
  std::string rule = "|";
  for(std::size_t c = 0; c < width.size(); ++c)
    rule += (right_align[c] ? std::string(width[c] + 1, '-') + ":|" : ":" + std::string(width[c] + 1, '-') + "|");
  std::printf("%s\n", rule.c_str());
  for(std::size_t r = 1; r < table.size(); ++r)
    print_row(table[r]);
}

/// Joins a command line for display.
std::string join_command(const std::vector<std::string>& words)
{
  std::string text;
  for(const std::string& w : words)
    text += (text.empty() ? "" : " ") + w;
  return text;
}

/// Prints the whole report (settings, table, totals, notes) on stdout.
void print_report(const Options& options, const std::vector<Row>& rows)
{
  std::vector<std::string> ours_command = {options.ours, "--quiet"};
  ours_command.insert(ours_command.end(), options.ours_arguments.begin(), options.ours_arguments.end());
  std::vector<std::string> peer_command = {options.peer};
  peer_command.insert(peer_command.end(), options.peer_arguments.begin(), options.peer_arguments.end());

  std::printf("\n## Normal orientation: ours vs CGAL::mst_orient_normals\n\n");
  std::printf("- ours: `%s IN OUT`\n", join_command(ours_command).c_str());
  std::printf("- CGAL: `%s IN OUT`\n", join_command(peer_command).c_str());
  std::string noises;
  for(double n : options.noises)
    noises += (noises.empty() ? "" : ", ") + format("%g", n);
  std::printf("- clouds: %zu area-uniform samples per mesh, noise %s (x bbox diagonal, per coordinate), "
              "seed %llu, PCA normals (k = 18) with random signs\n",
              options.points, noises.c_str(), static_cast<unsigned long long>(options.seed));
  std::printf("- wrong: dot(n_out, n_true) <= 0; s: wall clock of the whole program (read, orient, write); "
              "MB: peak RSS (wait4 ru_maxrss); %u hardware threads\n\n",
              std::thread::hardware_concurrency());

  std::vector<std::vector<std::string>> table;
  table.push_back({"mesh", "points", "noise", "ours s", "ours MB", "ours wrong", "CGAL s", "CGAL MB", "CGAL wrong",
                   "CGAL/ours time", "CGAL/ours mem"});
  std::size_t total_points = 0, ours_wrong = 0, cgal_wrong = 0, failed_rows = 0;
  double ours_seconds = 0.0, cgal_seconds = 0.0, ours_peak = 0.0, cgal_peak = 0.0;
  for(const Row& row : rows)
  {
    auto side_cells = [&](const Side_result& s) {
      return std::vector<std::string>{format("%.2f", s.child.seconds), format("%.1f", s.child.peak_mb),
                                      s.ok ? format_wrong(s.wrong, row.points) + (s.unstable ? " (!)" : "")
                                           : std::string("FAILED")};
    };
    std::vector<std::string> cells = {row.mesh, format("%zu", row.points), format("%g", row.noise)};
    for(const std::string& c : side_cells(row.ours))
      cells.push_back(c);
    for(const std::string& c : side_cells(row.cgal))
      cells.push_back(c);
    const bool both = row.ours.ok && row.cgal.ok;
    cells.push_back(both ? format_ratio(row.cgal.child.seconds, row.ours.child.seconds) : "-");
    cells.push_back(both ? format_ratio(row.cgal.child.peak_mb, row.ours.child.peak_mb) : "-");
    table.push_back(cells);
    if(!both)
    {
      ++failed_rows;
      continue;
    }
    total_points += row.points;
    ours_wrong += row.ours.wrong;
    cgal_wrong += row.cgal.wrong;
    ours_seconds += row.ours.child.seconds;
    cgal_seconds += row.cgal.child.seconds;
    ours_peak = (std::max)(ours_peak, row.ours.child.peak_mb);
    cgal_peak = (std::max)(cgal_peak, row.cgal.child.peak_mb);
  }
  table.push_back({"**total**", format("%zu", total_points), "", format("%.2f", ours_seconds),
                   format("%.1f", ours_peak), format_wrong(ours_wrong, total_points), format("%.2f", cgal_seconds),
                   format("%.1f", cgal_peak), format_wrong(cgal_wrong, total_points),
                   format_ratio(cgal_seconds, ours_seconds), format_ratio(cgal_peak, ours_peak)});
  print_markdown_table(table, {false, true, true, true, true, true, true, true, true, true, true});

  std::printf("\nTotals: rows where both programs succeeded; s = sum of times, MB = largest peak, "
              "time ratio = ratio of the sums, mem ratio = ratio of the largest peaks.\n");
  if(options.repeat > 1)
    std::printf("Each program ran %u times per cloud: s = fastest run, MB = largest peak; (!) = the number of "
                "wrong normals changed between runs (the first run is shown).\n",
                options.repeat);
  if(failed_rows > 0)
  {
    std::printf("\n%zu row(s) FAILED and are left out of the totals:\n", failed_rows);
    for(const Row& row : rows)
    {
      if(!row.ours.ok)
        std::printf("- %s, noise %g, ours: %s\n", row.mesh.c_str(), row.noise, row.ours.failure.c_str());
      if(!row.cgal.ok)
        std::printf("- %s, noise %g, CGAL: %s\n", row.mesh.c_str(), row.noise, row.cgal.failure.c_str());
    }
  }
}

/// Creates the working directory: `keep` (created if needed) or a fresh temporary one.
std::string make_work_directory(const std::string& keep)
{
  if(!keep.empty())
  {
    fs::create_directories(keep);
    return keep;
  }
  std::string pattern = (fs::temp_directory_path() / "compare_cgal.XXXXXX").string();
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  if(::mkdtemp(buffer.data()) == nullptr)
    throw std::runtime_error(std::string("mkdtemp: ") + std::strerror(errno));
  return std::string(buffer.data());
}

/// Returns true if `path` names an executable regular file.
bool is_executable(const std::string& path)
{
  struct stat info;
  return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

/// Runs one program through the spawner and evaluates it; on failure, appends the reason,
/// the command and the tail of the program's stderr to `failure_report`.
Side_result run_side(Child_spawner& spawner, const std::string& label, const std::vector<std::string>& command,
                     const std::string& output_path, const std::string& log_prefix, const Sampled_cloud& cloud,
                     double tolerance, std::string& failure_report)
{
  const std::string stdout_path = log_prefix + ".stdout";
  const std::string stderr_path = log_prefix + ".stderr";
  const Child_result child = spawner.run(command, stdout_path, stderr_path);
  const Side_result side = evaluate(child, output_path, cloud, tolerance);
  if(!side.ok)
  {
    failure_report += "  " + label + " FAILED: " + side.failure + "\n  command: " + join_command(command) + "\n";
    const std::string tail = file_tail(stderr_path, 20);
    if(!tail.empty())
    {
      std::string indented = "    " + tail;
      for(std::size_t p = indented.find('\n'); p != std::string::npos; p = indented.find('\n', p + 1))
        indented.insert(p + 1, "    ");
      failure_report += "  stderr (tail):\n" + indented + "\n";
    }
  }
  return side;
}

/// Samples `sampler` at `options.points` points and `noise`, runs both
/// programs on the cloud (alternately, `options.repeat` times) and scores
/// them; removes the files unless `keep`.
Row run_cloud(Child_spawner& spawner, const Options& options, Mesh_sampler& sampler, const std::string& mesh_name,
              double noise, const std::string& work_directory, bool keep)
{
  Sampling_options sampling;
  sampling.number_of_points = options.points;
  sampling.noise = noise;
  sampling.seed = options.seed;
  const auto generation_start = std::chrono::steady_clock::now();
  const Sampled_cloud cloud = sampler.sample(sampling);
  const std::string prefix =
    (fs::path(work_directory) / (mesh_name + "_" + std::to_string(options.points) + "_noise"
                                 + format("%g", noise)))
      .string();
  write_cloud(cloud, prefix);
  std::fprintf(stderr, "cloud %.2f s",
               std::chrono::duration<double>(std::chrono::steady_clock::now() - generation_start).count());
  std::fflush(stderr);

  // Files hold 9 significant digits; this only has to detect a changed point order.
  double magnitude = cloud.bbox_diagonal;
  for(const Point_3& p : cloud.points)
    magnitude = (std::max)({magnitude, std::abs(p.x()), std::abs(p.y()), std::abs(p.z())});
  const double tolerance = 1e-5 * magnitude;

  const std::string input = prefix + ".xyz";
  const std::string ours_output = prefix + ".ours.xyz";
  const std::string cgal_output = prefix + ".cgal.xyz";
  std::vector<std::string> ours_command = {options.ours, "--quiet"};
  ours_command.insert(ours_command.end(), options.ours_arguments.begin(), options.ours_arguments.end());
  ours_command.insert(ours_command.end(), {input, ours_output});
  std::vector<std::string> cgal_command = {options.peer};
  cgal_command.insert(cgal_command.end(), options.peer_arguments.begin(), options.peer_arguments.end());
  cgal_command.insert(cgal_command.end(), {input, cgal_output});

  Row row{mesh_name, options.points, noise, {}, {}};
  std::string failure_report;
  // Alternate the two programs so that a load change on the machine hits both alike.
  struct Side
  {
    const char* name;
    const std::vector<std::string>* command;
    const std::string* output;
    const char* suffix;
    Side_result* result;
  };
  const Side sides[2] = {{"ours", &ours_command, &ours_output, ".ours", &row.ours},
                         {"CGAL", &cgal_command, &cgal_output, ".cgal", &row.cgal}};
  for(unsigned int r = 0; r < options.repeat; ++r)
    for(const Side& side : sides)
    {
      if(r > 0 && !side.result->ok)
        continue;
      const Side_result run = run_side(spawner, side.name, *side.command, *side.output,
                                       prefix + side.suffix, cloud, tolerance, failure_report);
      if(r == 0)
        *side.result = run;
      else
        merge_repeat(*side.result, run);
    }
  std::fprintf(stderr, ", ours %.2f s%s, CGAL %.2f s%s\n%s", row.ours.child.seconds,
               row.ours.ok ? "" : " (FAILED)", row.cgal.child.seconds, row.cgal.ok ? "" : " (FAILED)",
               failure_report.c_str());
  if(!keep)
    for(const char* suffix : {".xyz", ".gt.xyz", ".ours.xyz", ".cgal.xyz", ".ours.stdout", ".ours.stderr",
                              ".cgal.stdout", ".cgal.stderr"})
    {
      std::error_code ec;
      fs::remove(prefix + suffix, ec);
    }
  return row;
}

} // namespace

/// Entry point: see print_usage().
int main(int argc, char** argv)
{
  Options options;
  bool help = false;
  if(!parse_options(argc, argv, options, help))
  {
    print_usage(stderr);
    return 2;
  }
  if(help)
  {
    print_usage(stdout);
    return 0;
  }
  ::signal(SIGPIPE, SIG_IGN);

  std::vector<std::string> meshes;
  try
  {
    meshes = collect_meshes(options.mesh_arguments);
  }
  catch(const std::exception& e)
  {
    std::fprintf(stderr, "compare_cgal: %s\n", e.what());
    return 2;
  }
  if(!is_executable(options.ours))
  {
    std::fprintf(stderr,
                 "compare_cgal: our program '%s' is missing or not executable; build the example "
                 "orient_normals or pass --ours PATH\n",
                 options.ours.c_str());
    return 2;
  }
  if(!is_executable(options.peer))
  {
    std::fprintf(stderr, "compare_cgal: peer program '%s' is missing or not executable; build cgal_mst_orient "
                 "or pass --peer PATH\n", options.peer.c_str());
    return 2;
  }

  std::string work_directory;
  std::vector<Row> rows;
  try
  {
    // Before any large allocation and before TBB starts threads (see Child_spawner).
    Child_spawner spawner;
    work_directory = make_work_directory(options.keep_directory);
    const bool keep = !options.keep_directory.empty();
    std::fprintf(stderr, "compare_cgal: %zu mesh(es) x %zu noise level(s), %zu points, working in %s\n",
                 meshes.size(), options.noises.size(), options.points, work_directory.c_str());

    const std::size_t total_runs = meshes.size() * options.noises.size();
    std::size_t run_index = 0;
    for(const std::string& mesh_path : meshes)
    {
      const std::string mesh_name = fs::path(mesh_path).stem().string();
      std::unique_ptr<Mesh_sampler> sampler;
      try
      {
        sampler = std::make_unique<Mesh_sampler>(mesh_path);
      }
      catch(const std::exception& e)
      {
        std::fprintf(stderr, "compare_cgal: skipping mesh: %s\n", e.what());
        for(double noise : options.noises)
        {
          Row row{mesh_name, options.points, noise, {}, {}};
          row.ours.failure = row.cgal.failure = std::string("mesh not readable: ") + e.what();
          rows.push_back(row);
          ++run_index;
        }
        continue;
      }
      for(double noise : options.noises)
      {
        ++run_index;
        std::fprintf(stderr, "[%zu/%zu] %s, %zu points, noise %g: ", run_index, total_runs, mesh_name.c_str(),
                     options.points, noise);
        std::fflush(stderr);

        rows.push_back(run_cloud(spawner, options, *sampler, mesh_name, noise, work_directory, keep));
      }
    }
  }
  catch(const std::exception& e)
  {
    std::fprintf(stderr, "\ncompare_cgal: %s\n", e.what());
    if(!work_directory.empty() && options.keep_directory.empty())
    {
      std::error_code ec;
      fs::remove_all(work_directory, ec);
    }
    return 1;
  }

  if(options.keep_directory.empty())
  {
    std::error_code ec;
    fs::remove_all(work_directory, ec);
  }
  else
    std::fprintf(stderr, "compare_cgal: clouds, outputs and logs kept in %s\n", work_directory.c_str());

  print_report(options, rows);
  const bool all_ok = std::all_of(rows.begin(), rows.end(), [](const Row& r) { return r.ours.ok && r.cgal.ok; });
  return all_ok ? 0 : 1;
}
