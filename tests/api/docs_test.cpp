// docs/api.md must describe every command and every error code the server can send.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "api/commands.hpp"
#include "api/fake_backend.hpp"

namespace liftd::api {
namespace {

std::string read_docs() {
  std::ifstream in(API_DOCS_PATH);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(ApiDocs, EveryCommandHasASection) {
  const std::string docs = read_docs();
  ASSERT_FALSE(docs.empty()) << API_DOCS_PATH;
  testing::FakeBackend backend;
  Dispatcher dispatcher;
  add_builtin_commands(dispatcher, backend);
  for (const auto& name : dispatcher.names()) {
    EXPECT_NE(docs.find("### `" + name + "`"), std::string::npos) << name << " is not documented";
  }
}

TEST(ApiDocs, EveryErrorCodeIsListed) {
  const std::string docs = read_docs();
  for (int i = 0; i <= static_cast<int>(ErrorCode::Internal); ++i) {
    const auto name = std::string(to_string(static_cast<ErrorCode>(i)));
    EXPECT_NE(docs.find("| `" + name + "`"), std::string::npos) << name << " is not in the table";
  }
}

TEST(ApiDocs, EveryInputIsListed) {
  const std::string docs = read_docs();
  for (const auto& flag : kInputFlags) {
    EXPECT_NE(docs.find("| `" + std::string(flag.name) + "`"), std::string::npos) << flag.name;
  }
}

TEST(ApiSchema, RequestsMatchTheCommandTable) {
  std::ifstream in(API_SCHEMA_PATH);
  const auto schema = nlohmann::json::parse(in);
  const auto& defs = schema.at("$defs");
  testing::FakeBackend backend;
  Dispatcher dispatcher;
  add_builtin_commands(dispatcher, backend);
  for (const auto& name : dispatcher.names()) {
    const auto it = defs.find("request_" + name);
    ASSERT_NE(it, defs.end()) << name << " has no request schema";
    const auto& props = it->at("properties");
    const CommandSpec& spec = *dispatcher.find(name);
    EXPECT_EQ(props.size(), spec.args.size() + 2) << name << ": fields differ (besides cmd, id)";
    auto required = it->at("required");
    for (const auto& arg : spec.args) {
      ASSERT_TRUE(props.contains(arg.name)) << name << "." << arg.name << " missing in schema";
      const auto& p = props.at(arg.name);
      const bool listed = std::find(required.begin(), required.end(), arg.name) != required.end();
      EXPECT_EQ(listed, arg.required) << name << "." << arg.name;
      switch (arg.type) {
        case ArgType::Bool:
          EXPECT_EQ(p.at("type"), "boolean") << name << "." << arg.name;
          break;
        case ArgType::Integer:
          EXPECT_EQ(p.at("type"), "integer") << name << "." << arg.name;
          EXPECT_EQ(p.at("minimum"), arg.min) << name << "." << arg.name;
          EXPECT_EQ(p.at("maximum"), arg.max) << name << "." << arg.name;
          break;
        case ArgType::String:
          EXPECT_EQ(p.at("enum"), nlohmann::json(arg.choices)) << name << "." << arg.name;
          break;
        case ArgType::Any:
          break;
      }
    }
  }
}

}  // namespace
}  // namespace liftd::api
