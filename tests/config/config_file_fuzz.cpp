// libFuzzer target: the config loader on files of every kind. The first byte picks what the
// path is (a regular file with the rest as its text, a symbolic link to it, a FIFO, a directory,
// a character device); load_file must return at once (a FIFO must not block: the fuzzer's
// timeout catches a hang), report the same problems for a file and a link to it, and read no
// non-regular file.
#include <sys/stat.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>
#include <string_view>

#include "config/config.hpp"
#include "kinds/config_schema.hpp"

namespace {

std::string all(const liftd::config::LoadResult& r) {
  std::string out;
  for (const auto& p : r.problems) out += p.message + "\n";
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string dir = [] {
    char tmpl[] = "/tmp/liftd-config-fuzz-XXXXXX";
    return std::string(::mkdtemp(tmpl));
  }();
  const std::string file = dir + "/liftd.json";
  const std::string link = dir + "/link.json";
  const std::string fifo = dir + "/fifo.json";
  const std::uint8_t kind = size > 0 ? data[0] % 4 : 0;
  const std::string_view text =
      size > 0 ? std::string_view(reinterpret_cast<const char*>(data + 1), size - 1) : "";
  ::unlink(file.c_str());
  ::unlink(link.c_str());
  ::unlink(fifo.c_str());
  std::ofstream(file, std::ios::binary) << text;
  switch (kind) {
    case 0: {  // a regular file and a link to it: the same outcome
      if (::symlink(file.c_str(), link.c_str()) != 0) std::abort();
      const auto direct = liftd::kinds::load_config(file);
      const auto via_link = liftd::kinds::load_config(link);
      if (all(direct) != all(via_link)) std::abort();
      break;
    }
    case 1: {  // a FIFO nobody writes to
      if (::mkfifo(fifo.c_str(), 0600) != 0) std::abort();
      if (liftd::kinds::load_config(fifo).problems.size() != 1) std::abort();
      break;
    }
    case 2:  // a directory
      if (liftd::kinds::load_config(dir).problems.size() != 1) std::abort();
      break;
    default:  // a character device that would never end
      if (liftd::kinds::load_config("/dev/zero").problems.size() != 1) std::abort();
      break;
  }
  return 0;
}
