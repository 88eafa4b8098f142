// A gtest fixture that runs the gradus binary (GRADUS_BIN) in a per-test
// temporary directory: write scene files, run with arguments, read stderr,
// the exit status and the wall time.
#pragma once
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace gradus::test {

struct RunResult {
    int status;
    std::string err;
    double wall = 0;  // seconds
};

class GradusCliTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = std::filesystem::temp_directory_path() /
               ("gradus_cli_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }
    std::string write(const std::string &name, const std::string &text) {
        std::ofstream(dir_ / name) << text;
        return (dir_ / name).string();
    }
    RunResult run(const std::string &args) {
        std::string errFile = (dir_ / "stderr.txt").string();
        std::string cmd =
            "cd '" + dir_.string() + "' && '" + GRADUS_BIN + "' " + args + " 2> '" + errFile + "' > /dev/null";
        auto t0 = std::chrono::steady_clock::now();
        int st = std::system(cmd.c_str());
        double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::ifstream in(errFile);
        std::stringstream ss;
        ss << in.rdbuf();
        return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, ss.str(), wall};
    }
    std::filesystem::path dir_;
};

}  // namespace gradus::test
