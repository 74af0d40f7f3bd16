// The system-call allow list of liftd.service is complete: liftd --simulate runs under a seccomp
// filter built from exactly the unit's SystemCallFilter= lines (groups expanded by
// systemd-analyze, as systemd does), comes up, answers the API, travels, saves nothing it should
// not, and stops cleanly on SIGTERM. A call outside the list kills it with SIGSYS, as under
// systemd. This machine has no systemd as PID 1, so the unit itself cannot start here.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "e2e/harness.hpp"

namespace liftd::e2e {
namespace {

/// Lines of `command`'s standard output; empty when it could not run.
std::vector<std::string> output_lines(const std::string& command) {
  std::vector<std::string> lines;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return lines;
  std::array<char, 512> buffer{};
  std::string text;
  while (std::fgets(buffer.data(), static_cast<int>(buffer.size()), pipe) != nullptr) {
    text += buffer.data();
  }
  ::pclose(pipe);
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// The system-call names of `item` (a name, or a @group expanded recursively).
void expand(const std::string& item, std::set<std::string>& out, std::set<std::string>& seen) {
  if (item.empty() || item[0] != '@') {
    out.insert(item);
    return;
  }
  if (!seen.insert(item).second) return;
  for (const std::string& line :
       output_lines("systemd-analyze syscall-filter --no-pager " + item)) {
    const auto start = line.find_first_not_of(' ');
    if (start == std::string::npos || start == 0) continue;  // the group's own header line
    const std::string name = line.substr(start);
    if (name[0] == '#') continue;
    expand(name, out, seen);
  }
}

/// The allow list the unit's SystemCallFilter= lines give: allow lines add, "~" lines remove.
std::set<std::string> unit_allow_list(const std::string& unit) {
  std::set<std::string> allowed;
  std::ifstream in(unit);
  std::set<std::string> seen;
  for (std::string line; std::getline(in, line);) {
    const std::string key = "SystemCallFilter=";
    if (line.rfind(key, 0) != 0) continue;
    std::string value = line.substr(key.size());
    const bool deny = !value.empty() && value[0] == '~';
    if (deny) value.erase(0, 1);
    std::istringstream items(value);
    for (std::string item; items >> item;) {
      std::set<std::string> names;
      std::set<std::string> seen_here;
      expand(item, names, seen_here);
      for (const auto& n : names) deny ? (void)allowed.erase(n) : (void)allowed.insert(n);
    }
  }
  return allowed;
}

TEST(SyscallFilter, LiftdRunsATravelAndStopsUnderTheUnitsAllowList) {
  if (output_lines("command -v systemd-analyze").empty()) {
    GTEST_SKIP() << "systemd-analyze is not installed: cannot expand the unit's groups";
  }
  const std::set<std::string> names = unit_allow_list(LIFTD_UNIT);
  ASSERT_GT(names.size(), 100u) << "no SystemCallFilter= allow list in " << LIFTD_UNIT;
  EXPECT_EQ(names.count("sched_setscheduler"), 1u) << "the cycle thread needs SCHED_FIFO";
  EXPECT_EQ(names.count("reboot"), 0u) << "@privileged must stay denied";

  // SQLite (the lift's record) gives a journal or WAL file its database's owner with fchown(2),
  // which @privileged denies, but only when it runs as root (its unix VFS checks geteuid()).
  // The unit runs liftd as user liftd, so it never makes that call; this test runs as root.
  std::set<std::string> filter = names;
  if (::geteuid() == 0) filter.insert("fchown");

  std::map<std::string, unsigned> numbers;
  std::ifstream table(SYSCALL_NUMBERS);
  std::string name;
  for (unsigned n = 0; table >> name >> n;) numbers[name] = n;
  ASSERT_GT(numbers.size(), 200u) << "no system-call numbers in " << SYSCALL_NUMBERS;
  const std::string list_path =
      std::filesystem::temp_directory_path() / ("liftd-seccomp-" + std::to_string(::getpid()));
  {
    std::ofstream list(list_path);
    for (const auto& n : filter) {
      // Names of other architectures (e.g. arm_fadvise64_64) have no number here.
      if (const auto it = numbers.find(n); it != numbers.end()) list << it->second << "\n";
    }
  }

  Lift lift("seccomp", 4, json::object(), {SECCOMP_EXEC, list_path});
  ASSERT_EQ(lift.setup_error(), "") << lift.log();
  const json travel = lift.call({{"cmd", "travel"}, {"floor", 2}});
  ASSERT_TRUE(travel.value("ok", false)) << travel.dump();
  const json end = lift.wait_travel_end();
  ASSERT_FALSE(end.is_null()) << "no end of travel: " << lift.log();
  EXPECT_EQ(end["data"]["event"], "finished") << end.dump();
  const json saved = lift.call({{"cmd", "trace"}, {"save", true}});
  EXPECT_TRUE(saved.value("ok", false)) << saved.dump();
  for (const char* cmd : {"status", "stats", "trace", "config", "display", "version"}) {
    const json reply = lift.call({{"cmd", cmd}});
    EXPECT_TRUE(reply.value("ok", false)) << cmd << ": " << reply.dump();
  }
  // A SIGSYS kill shows as 128 + 31; a clean stop as 0.
  const auto code = lift.stop_daemon(SIGTERM, 30s);
  ASSERT_TRUE(code.has_value()) << "liftd did not stop";
  EXPECT_EQ(*code, 0) << (*code == 128 + SIGSYS ? "killed by SIGSYS: a system call outside the "
                                                  "unit's SystemCallFilter= (see dmesg/audit)\n"
                                                : "")
                      << lift.log();
  std::filesystem::remove(list_path);
}

}  // namespace
}  // namespace liftd::e2e
