// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_BENCHMARK_BENCHMARK_OPTIONS_H
#define NORMAL_ORIENTATION_BENCHMARK_BENCHMARK_OPTIONS_H

/// \file Benchmark_options.h
/// Command-line helpers shared by the benchmark programs: the list of noise
/// levels and the list of meshes.  `NORMAL_ORIENTATION_BENCHMARK_MESH_DIR`
/// (the default mesh directory) is defined by benchmark/CMakeLists.txt.

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#ifndef NORMAL_ORIENTATION_BENCHMARK_MESH_DIR
#error "NORMAL_ORIENTATION_BENCHMARK_MESH_DIR must be defined (see benchmark/CMakeLists.txt)"
#endif

namespace Normal_orientation {
namespace benchmark {

/// Parses a comma-separated list of noise levels in [0, 1); returns false on a bad entry.
inline bool parse_noise_list(const std::string& text, std::vector<double>& values)
{
  values.clear();
  std::size_t begin = 0;
  while(begin <= text.size())
  {
    std::size_t end = text.find(',', begin);
    if(end == std::string::npos)
      end = text.size();
    const std::string item = text.substr(begin, end - begin);
    char* stop = nullptr;
    const double value = std::strtod(item.c_str(), &stop);
    if(item.empty() || *stop != '\0' || !(value >= 0.0) || !(value < 1.0))
      return false;
    values.push_back(value);
    begin = end + 1;
  }
  return !values.empty();
}

/// Expands the --meshes arguments (or the default directory) into a list of mesh files.
/// \throws std::runtime_error with a clear message when nothing usable is found.
inline std::vector<std::string> collect_meshes(const std::vector<std::string>& arguments)
{
  std::vector<std::string> inputs = arguments;
  if(inputs.empty())
  {
    std::error_code ec;
    if(!std::filesystem::is_directory(NORMAL_ORIENTATION_BENCHMARK_MESH_DIR, ec))
      throw std::runtime_error("the default mesh directory '" NORMAL_ORIENTATION_BENCHMARK_MESH_DIR
                               "' does not exist; pass --meshes DIR_OR_FILES...");
    inputs.push_back(NORMAL_ORIENTATION_BENCHMARK_MESH_DIR);
  }
  std::vector<std::string> meshes;
  for(const std::string& input : inputs)
  {
    std::error_code ec;
    if(std::filesystem::is_directory(input, ec))
    {
      std::vector<std::string> found;
      for(const std::filesystem::directory_entry& entry : std::filesystem::directory_iterator(input, ec))
        if(entry.is_regular_file() && entry.path().extension() == ".off")
          found.push_back(entry.path().string());
      if(found.empty())
        throw std::runtime_error("no .off file in directory '" + input + "'");
      std::sort(found.begin(), found.end());
      meshes.insert(meshes.end(), found.begin(), found.end());
    }
    else if(std::filesystem::is_regular_file(input, ec))
      meshes.push_back(input);
    else
      throw std::runtime_error("mesh '" + input + "' is neither a file nor a directory");
  }
  return meshes;
}

/// Parses the unsigned decimal `text` into `value`; returns false unless it lies in [minimum, maximum].
inline bool parse_unsigned(const char* text, unsigned long long minimum, unsigned long long maximum,
                           unsigned long long& value)
{
  char* stop = nullptr;
  value = std::strtoull(text, &stop, 10);
  return text[0] != '-' && stop != text && *stop == '\0' && value >= minimum && value <= maximum;
}

/// The options that say which clouds a benchmark generates; each program's options derive from it
/// and set their own default noise levels.
struct Cloud_options
{
  /// Mesh files and directories given with --meshes (empty: the default directory).
  std::vector<std::string> mesh_arguments;
  /// Points per cloud.
  std::size_t points = 30000;
  /// Noise levels (fractions of the bounding-box diagonal).
  std::vector<double> noises;
  /// Seed of every cloud.
  std::uint64_t seed = 1;
};

/// Parses argv[i] if it is one of --meshes, --points, --noise, --seed (advancing `i` over its
/// values).  Returns 1 when parsed, 0 when argv[i] is not one of them, -1 on a bad value (after
/// printing why, prefixed with `program`).
inline int parse_cloud_option(int argc, char** argv, int& i, Cloud_options& options, const char* program)
{
  const std::string arg = argv[i];
  const bool has_value = i + 1 < argc;
  unsigned long long value = 0;
  if(arg == "--meshes")
  {
    while(i + 1 < argc && std::strncmp(argv[i + 1], "--", 2) != 0)
      options.mesh_arguments.push_back(argv[++i]);
    if(options.mesh_arguments.empty())
    {
      std::fprintf(stderr, "%s: --meshes needs at least one file or directory\n", program);
      return -1;
    }
    return 1;
  }
  if(arg == "--points" && has_value)
  {
    if(!parse_unsigned(argv[++i], 1, static_cast<unsigned long long>(SIZE_MAX), value))
    {
      std::fprintf(stderr, "%s: invalid --points '%s'\n", program, argv[i]);
      return -1;
    }
    options.points = static_cast<std::size_t>(value);
    return 1;
  }
  if(arg == "--noise" && has_value)
  {
    if(!parse_noise_list(argv[++i], options.noises))
    {
      std::fprintf(stderr, "%s: invalid --noise '%s' (expected e.g. 0,0.005)\n", program, argv[i]);
      return -1;
    }
    return 1;
  }
  if(arg == "--seed" && has_value)
  {
    if(!parse_unsigned(argv[++i], 0, UINT64_MAX, value))
    {
      std::fprintf(stderr, "%s: invalid --seed '%s'\n", program, argv[i]);
      return -1;
    }
    options.seed = static_cast<std::uint64_t>(value);
    return 1;
  }
  return 0;
}

} // namespace benchmark
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_BENCHMARK_BENCHMARK_OPTIONS_H
