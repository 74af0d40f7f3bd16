// Runs a program as a child process with a chosen environment, its stdout and stderr going to
// files, for the end-to-end daemon tests. Header-only.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace liftd::testing {

/// A child process; killed on destruction if still running.
class Process {
 public:
  /// Starts `args[0]` with `args` and exactly the environment `env` ("KEY=value"); output goes
  /// to `<dir>/<name>.out` and `<dir>/<name>.err`.
  /// With `stderr_fd` >= 0 the child's stderr is that descriptor instead of the file.
  /// With `stdin_pipe` the child's stdin is a pipe write_stdin() writes to (a simulator's
  /// command line); otherwise it inherits the test's.
  Process(const std::vector<std::string>& args, const std::vector<std::string>& env,
          const std::string& dir, const std::string& name = "child", int stderr_fd = -1,
          bool stdin_pipe = false)
      : out_path_(dir + "/" + name + ".out"), err_path_(dir + "/" + name + ".err") {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    int in[2] = {-1, -1};
    if (stdin_pipe) {
      if (::pipe2(in, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
      posix_spawn_file_actions_adddup2(&actions, in[0], 0);
      stdin_fd_ = in[1];
    }
    posix_spawn_file_actions_addopen(&actions, 1, out_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    if (stderr_fd >= 0) {
      posix_spawn_file_actions_adddup2(&actions, stderr_fd, 2);
    } else {
      posix_spawn_file_actions_addopen(&actions, 2, err_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                       0644);
    }
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    std::vector<char*> envp;
    for (const auto& e : env) envp.push_back(const_cast<char*>(e.c_str()));
    envp.push_back(nullptr);
    const int error = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&actions);
    if (in[0] >= 0) ::close(in[0]);
    if (error != 0) throw std::runtime_error("posix_spawn failed for " + args[0]);
  }
  ~Process() {
    if (stdin_fd_ >= 0) ::close(stdin_fd_);
    if (!status_) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      ::waitpid(pid_, &status, 0);
    }
  }
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  /// Writes `text` to the child's stdin pipe (see the constructor); false when that failed.
  bool write_stdin(const std::string& text) {
    if (stdin_fd_ < 0) return false;
    return ::write(stdin_fd_, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  }

  /// Sends a signal.
  void signal(int signal_number) { ::kill(pid_, signal_number); }
  /// The process id.
  pid_t pid() const { return pid_; }

  /// The exit code (128 + signal when killed), or nullopt if still running after `timeout`.
  std::optional<int> wait(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (!status_) {
      int status = 0;
      const pid_t done = ::waitpid(pid_, &status, WNOHANG);
      if (done == pid_) {
        status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        break;
      }
      if (std::chrono::steady_clock::now() >= end) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return status_;
  }

  /// Everything written to stdout so far.
  std::string out() const { return read(out_path_); }
  /// Everything written to stderr so far.
  std::string err() const { return read(err_path_); }

 private:
  static std::string read(const std::string& path) {
    std::ifstream in(path);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }

  pid_t pid_ = -1;
  std::optional<int> status_;
  std::string out_path_;
  std::string err_path_;
  int stdin_fd_ = -1;
};

}  // namespace liftd::testing
