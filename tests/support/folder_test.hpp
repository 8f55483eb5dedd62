// SPDX-License-Identifier: LGPL-2.1-or-later
// A GoogleTest fixture with a fresh folder per test, for tests that write model files.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <utility>

namespace pickdetect::test_scene {

/// A fresh folder per test (`prefix`, the process id and the test's name, under the temporary
/// directory), removed afterwards.
class FolderTest : public ::testing::Test {
protected:
  explicit FolderTest(std::string prefix) : prefix_(std::move(prefix)) {}
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           (prefix_ + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  /// Writes `text` to the file `name` of the folder; returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name)) << text;
    return path(name);
  }
  std::filesystem::path dir_;

private:
  std::string prefix_;
};

} // namespace pickdetect::test_scene
