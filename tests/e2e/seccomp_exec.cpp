// seccomp-exec FILE PROGRAM [ARGS...]: runs PROGRAM under a seccomp filter that allows exactly
// the system calls whose numbers FILE lists (one per line) and kills the process on any other,
// as systemd's SystemCallFilter= allow list does (its default action). For the test that proves
// the unit's filter complete where systemd itself cannot start the service.
#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <vector>

namespace {

#if defined(__x86_64__)
constexpr unsigned kArch = AUDIT_ARCH_X86_64;
#elif defined(__aarch64__)
constexpr unsigned kArch = AUDIT_ARCH_AARCH64;
#else
#error "seccomp-exec knows the audit architecture of x86_64 and aarch64 only"
#endif

sock_filter stmt(unsigned short code, unsigned k) {
  return sock_filter{code, 0, 0, k};
}
sock_filter jump(unsigned short code, unsigned k, unsigned char jt, unsigned char jf) {
  return sock_filter{code, jt, jf, k};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: seccomp-exec FILE PROGRAM [ARGS...]\n");
    return 2;
  }
  std::ifstream in(argv[1]);
  std::vector<unsigned> allowed;
  for (unsigned n = 0; in >> n;) allowed.push_back(n);
  if (allowed.empty()) {
    std::fprintf(stderr, "seccomp-exec: no system call numbers in %s\n", argv[1]);
    return 2;
  }
  std::vector<sock_filter> program;
  // Another architecture's calls (SystemCallArchitectures=native): kill.
  program.push_back(stmt(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, arch)));
  program.push_back(jump(BPF_JMP | BPF_JEQ | BPF_K, kArch, 1, 0));
  program.push_back(stmt(BPF_RET | BPF_K, SECCOMP_RET_KILL_PROCESS));
  program.push_back(stmt(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, nr)));
  for (const unsigned n : allowed) {
    program.push_back(jump(BPF_JMP | BPF_JEQ | BPF_K, n, 0, 1));  // equal: the next, allow
    program.push_back(stmt(BPF_RET | BPF_K, SECCOMP_RET_ALLOW));
  }
  program.push_back(stmt(BPF_RET | BPF_K, SECCOMP_RET_KILL_PROCESS));
  const sock_fprog fprog{static_cast<unsigned short>(program.size()), program.data()};
  if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 ||
      prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &fprog) != 0) {
    std::fprintf(stderr, "seccomp-exec: cannot install the filter: %s\n", std::strerror(errno));
    return 3;
  }
  execv(argv[2], argv + 2);
  std::fprintf(stderr, "seccomp-exec: cannot run %s: %s\n", argv[2], std::strerror(errno));
  return 127;
}
