#include "config/json_document.h"

#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <vector>

namespace drape::bake {
namespace {

using nlohmann::json;

// A SAX pass that tracks the JSON path of every value and stops at the first key an object
// repeats, or at the first error the parser reports (which it then explains with that path).
class StrictChecker final : public nlohmann::json_sax<json> {
 public:
  bool null() override { return Value(); }
  bool boolean(bool) override { return Value(); }
  bool number_integer(number_integer_t) override { return Value(); }
  bool number_unsigned(number_unsigned_t) override { return Value(); }
  bool number_float(number_float_t, const string_t&) override { return Value(); }
  bool string(string_t&) override { return Value(); }
  bool binary(binary_t&) override { return Value(); }
  bool start_object(std::size_t) override {
    Value();
    frames_.push_back({false, 0, {}, {}});
    return true;
  }
  bool key(string_t& key) override {
    Frame& top = frames_.back();
    top.key = key;
    if (!top.keys.insert(key).second) {
      reason_ = PathHere() + ": appears twice in its object";
      return false;
    }
    return true;
  }
  bool end_object() override {
    frames_.pop_back();
    return true;
  }
  bool start_array(std::size_t) override {
    Value();
    frames_.push_back({true, 0, {}, {}});
    return true;
  }
  bool end_array() override {
    frames_.pop_back();
    return true;
  }
  bool parse_error(std::size_t, const std::string& last_token,
                   const nlohmann::detail::exception& error) override {
    if (error.id == 406) {  // out_of_range: a number beyond a double
      if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
      reason_ = PathHere() + ": the number " + last_token + " is beyond what a double holds";
    } else {
      reason_ = std::string("not valid JSON: ") + error.what();
    }
    return false;
  }

  const std::string& reason() const { return reason_; }

 private:
  struct Frame {
    bool array;
    size_t index;  // arrays: the next element's index
    std::set<std::string> keys;
    std::string key;  // objects: the current member's key
  };

  // A value (or the start of a container) at the current place: an array moves to its next
  // element.
  bool Value() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
    return true;
  }
  // The JSON path of the current place: the key of each enclosing object's current member and
  // the index of each enclosing array's current element.
  std::string PathHere() const {
    std::string path;
    for (const Frame& f : frames_) {
      path += "/" + (f.array ? std::to_string(f.index == 0 ? 0 : f.index - 1) : f.key);
    }
    return path.empty() ? "/" : path;
  }

  std::vector<Frame> frames_;
  std::string reason_;
};

}  // namespace

Status ParseJsonText(std::string_view text, const std::string& source, nlohmann::json* out) {
  StrictChecker checker;
  if (!json::sax_parse(text, &checker)) {
    return Status(StatusCode::kInvalidArgument, source + ": " + checker.reason());
  }
  json parsed = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded()) {  // the checker accepted what the parser refuses: never expected
    return Status(StatusCode::kInvalidArgument, source + ": not valid JSON");
  }
  *out = std::move(parsed);
  return Status::Ok();
}

Status ReadJsonFile(const std::string& path, const std::string& what, nlohmann::json* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return Status(StatusCode::kIoError, path + ": cannot open the " + what + " file" +
                                            (std::filesystem::exists(path) ? "" : " (not found)"));
  }
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return Status(StatusCode::kIoError, path + ": cannot read the " + what + " file");
  return ParseJsonText(text, path, out);
}

}  // namespace drape::bake
