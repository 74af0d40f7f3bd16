// liftctl learn --apply: the learned levels written into a configuration file atomically, the
// old file kept as FILE.bak, every other key as it was; refusals write nothing.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "learn_apply.hpp"

namespace {

using nlohmann::json;
using nlohmann::ordered_json;

const char* const kConfigText = R"({
  "drive": {"kind": "dcp", "device": "/dev/ttyS1"},
  "floors": [
    {"name": "G", "level_mm": 0},
    {"name": "1", "level_mm": 500},
    {"name": "2", "level_mm": 1000}
  ],
  "api": {"socket": "/run/liftd/api.sock"}
}
)";

json learned(bool accepted = true) {
  json floors = json::array();
  const int configured[] = {0, 500, 1000};
  const int levels[] = {-35, 525, 1055};
  for (int i = 0; i < 3; ++i) {
    floors.push_back({{"floor", i},
                      {"name", i == 0 ? "G" : std::to_string(i)},
                      {"configured_mm", configured[i]},
                      {"learned_mm", levels[i]},
                      {"difference_mm", levels[i] - configured[i]},
                      {"zone_mm", 100}});
  }
  return {{"accepted", accepted},
          {"verdict", accepted ? "ok" : "zone_too_long"},
          {"reason", accepted ? "one plausible level zone per floor" : "level zone 1 is long"},
          {"zones_found", 3},
          {"floors", floors},
          {"takes_effect", "restart liftd"}};
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class LearnApply : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("liftctl-learn-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    file_ = dir_ / "liftd.json";
    std::ofstream(file_) << kConfigText;
    ::chmod(file_.c_str(), 0640);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::size_t files() const {
    return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(dir_),
                                                  std::filesystem::directory_iterator()));
  }

  std::filesystem::path dir_;
  std::filesystem::path file_;
};

TEST_F(LearnApply, WritesTheLearnedLevelsAndKeepsTheOldFile) {
  const liftctl::ApplyOutcome outcome = liftctl::apply_learned_levels(file_.string(), learned());
  ASSERT_TRUE(outcome.ok) << outcome.message;
  EXPECT_NE(outcome.message.find("liftd.json.bak"), std::string::npos) << outcome.message;
  EXPECT_EQ(read_text(file_.string() + ".bak"), kConfigText);
  const ordered_json now = ordered_json::parse(read_text(file_));
  const ordered_json before = ordered_json::parse(kConfigText);
  EXPECT_EQ(now["floors"][0]["level_mm"], -35);
  EXPECT_EQ(now["floors"][1]["level_mm"], 525);
  EXPECT_EQ(now["floors"][2]["level_mm"], 1055);
  EXPECT_EQ(now["floors"][1]["name"], "1");
  // Every other key as it was, in its order.
  ordered_json rest = now;
  rest.erase("floors");
  ordered_json rest_before = before;
  rest_before.erase("floors");
  EXPECT_EQ(rest.dump(), rest_before.dump());
  struct stat st {};
  ASSERT_EQ(::stat(file_.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640U);
  EXPECT_EQ(files(), 2U) << "no temporary file left behind";
}

TEST_F(LearnApply, ARefusedResultWritesNothing) {
  const liftctl::ApplyOutcome outcome =
      liftctl::apply_learned_levels(file_.string(), learned(false));
  EXPECT_FALSE(outcome.ok);
  EXPECT_NE(outcome.message.find("refused"), std::string::npos) << outcome.message;
  EXPECT_EQ(read_text(file_), kConfigText);
  EXPECT_EQ(files(), 1U);
}

TEST_F(LearnApply, AFileWithOtherFloorsIsLeftAlone) {
  json result = learned();
  result["floors"][1]["configured_mm"] = 510;  // the daemon ran another table
  const liftctl::ApplyOutcome outcome = liftctl::apply_learned_levels(file_.string(), result);
  EXPECT_FALSE(outcome.ok);
  EXPECT_NE(outcome.message.find("nothing written"), std::string::npos) << outcome.message;
  EXPECT_EQ(read_text(file_), kConfigText);
  EXPECT_EQ(files(), 1U);
  result = learned();
  result["floors"].erase(2);
  EXPECT_FALSE(liftctl::apply_learned_levels(file_.string(), result).ok);
  EXPECT_EQ(read_text(file_), kConfigText);
}

TEST_F(LearnApply, AMissingFileIsReported) {
  const liftctl::ApplyOutcome outcome =
      liftctl::apply_learned_levels((dir_ / "nope.json").string(), learned());
  EXPECT_FALSE(outcome.ok);
  EXPECT_NE(outcome.message.find("cannot read"), std::string::npos) << outcome.message;
}

TEST(LearnTable, ShowsEachFloorAndTheVerdict) {
  const std::string text = liftctl::format_learn_result(learned());
  EXPECT_NE(text.find("configured"), std::string::npos) << text;
  EXPECT_NE(text.find("525 mm"), std::string::npos) << text;
  EXPECT_NE(text.find("55 mm"), std::string::npos) << text;
  EXPECT_NE(text.find("accepted: one plausible level zone per floor"), std::string::npos) << text;
  EXPECT_NE(text.find("restart liftd"), std::string::npos) << text;
  EXPECT_NE(liftctl::format_learn_result(learned(false)).find("refused: "), std::string::npos);
}

}  // namespace
