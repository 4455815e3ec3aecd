// SPDX-License-Identifier: GPL-3.0-or-later
// A fresh temporary directory per test, removed with its content at the end:
// shared by the tests that write files.
#ifndef NORMAL_ORIENTATION_TEST_TEST_DIRECTORY_H
#define NORMAL_ORIENTATION_TEST_TEST_DIRECTORY_H

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <unistd.h>

namespace Normal_orientation {
namespace test {

/// \brief A fresh directory under the system's temporary directory, named after the
/// process, a counter and the running test; removed with its content on destruction.
class Test_directory
{
public:
  /// creates `<tmp>/<prefix><pid>_<counter>_<test name>`
  explicit Test_directory(const std::string& prefix)
  {
    static std::atomic<int> counter{0};
    const std::string name = prefix + std::to_string(::getpid()) + "_" + std::to_string(counter++) + "_" +
                             ::testing::UnitTest::GetInstance()->current_test_info()->name();
    m_path = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(m_path);
    std::filesystem::create_directories(m_path);
  }
  ~Test_directory()
  {
    std::error_code error;
    std::filesystem::remove_all(m_path, error);
  }
  Test_directory(const Test_directory&) = delete;
  Test_directory& operator=(const Test_directory&) = delete;

  /// the path of the directory
  std::string path() const { return m_path.string(); }
  /// the full name of file `name` in the directory
  std::string file(const std::string& name) const { return (m_path / name).string(); }
  /// the names of the entries of the directory, sorted
  std::vector<std::string> listing() const
  {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(m_path))
      names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  /// the number of entries in the directory
  std::size_t count() const { return listing().size(); }

protected:
  /// the directory
  std::filesystem::path m_path;
};

} // namespace test
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_TEST_TEST_DIRECTORY_H
