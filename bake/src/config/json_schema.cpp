#include "config/json_schema.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <utility>

#include "config/name_suggestions.h"

namespace drape::bake {

using nlohmann::json;

namespace {

const json& Null() {
  static const json null;
  return null;
}

std::string Quote(const std::string& s) { return "'" + s + "'"; }

// The markdown text of a default value: numbers shortest, strings in backticks, arrays in
// brackets, absent as "none".
std::string DefaultText(const json& value) {
  if (value.is_null()) return "none";
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number_unsigned()) return std::to_string(value.get<uint64_t>());
  if (value.is_number_integer()) return std::to_string(value.get<int64_t>());
  if (value.is_number()) return FormatNumber(value.get<double>());
  if (value.is_string()) {
    const std::string s = value.get<std::string>();
    return s.empty() ? "none" : "`" + s + "`";
  }
  if (value.is_array()) {
    std::string out;
    for (const json& element : value) {
      out += (out.empty() ? "" : ", ") +
             (element.is_string() ? "`" + element.get<std::string>() + "`" : DefaultText(element));
    }
    return "[" + out + "]";
  }
  return "see below";
}

// A markdown table cell: '|' escaped unless it is already.
std::string Cell(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '|' && (i == 0 || text[i - 1] != '\\')) out += '\\';
    out += text[i];
  }
  return out;
}

}  // namespace

JsonAt JsonAt::Member(const std::string& key) const {
  const json* member = Find(key);
  return JsonAt(member != nullptr ? *member : Null(), path_ + "/" + key, *document_);
}

JsonAt JsonAt::Element(size_t index) const {
  const json& element = value_->is_array() && index < value_->size() ? (*value_)[index] : Null();
  return JsonAt(element, path_ + "/" + std::to_string(index), *document_);
}

const json* JsonAt::Find(const std::string& key) const {
  if (!value_->is_object()) return nullptr;
  const auto it = value_->find(key);
  return it == value_->end() ? nullptr : &*it;
}

Status JsonAt::Error(const std::string& reason) const {
  return Status(StatusCode::kInvalidArgument,
                document_->source + ": " + (path_.empty() ? "/" : path_) + ": " + reason);
}

std::string NumberRange::Text() const {
  return std::string(lo_open ? "(" : "[") + FormatNumber(lo) + ", " + FormatNumber(hi) +
         (hi_open ? ")" : "]");
}

Status ReadDouble(const JsonAt& at, const NumberRange& range, double* out) {
  const json& v = at.value();
  if (!v.is_number()) {
    return at.Error("must be a number in " + range.Text() + ", not " + JsonTypeName(v));
  }
  const double x = v.get<double>();
  if (!std::isfinite(x) || x < range.lo || x > range.hi || (range.lo_open && x == range.lo) ||
      (range.hi_open && x == range.hi)) {
    return at.Error(FormatNumber(x) + " is out of range: must be in " + range.Text());
  }
  *out = x;
  return Status::Ok();
}

Status ReadFloat(const JsonAt& at, const NumberRange& range, float* out) {
  const json& v = at.value();
  if (!v.is_number()) {
    return at.Error("must be a number in " + range.Text() + ", not " + JsonTypeName(v));
  }
  const double x = v.get<double>();
  const float f = static_cast<float>(x);
  const float lo = static_cast<float>(range.lo), hi = static_cast<float>(range.hi);
  if (!std::isfinite(x) || !std::isfinite(f) || f < lo || f > hi || (range.lo_open && f == lo) ||
      (range.hi_open && f == hi)) {
    return at.Error(FormatNumber(x) + " is out of range: must be in " + range.Text());
  }
  *out = f;
  return Status::Ok();
}

Status ReadUnsigned(const JsonAt& at, uint64_t lo, uint64_t hi, uint64_t* out) {
  const json& v = at.value();
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  if (!v.is_number_integer()) {
    return at.Error("must be an integer in " + range + ", not " +
                    (v.is_number() ? "a fraction" : JsonTypeName(v)));
  }
  if (v.is_number_unsigned()) {
    const uint64_t x = v.get<uint64_t>();
    if (x < lo || x > hi)
      return at.Error(std::to_string(x) + " is out of range: must be in " + range);
    *out = x;
    return Status::Ok();
  }
  const int64_t x = v.get<int64_t>();
  if (x < 0 || static_cast<uint64_t>(x) < lo || static_cast<uint64_t>(x) > hi)
    return at.Error(std::to_string(x) + " is out of range: must be in " + range);
  *out = static_cast<uint64_t>(x);
  return Status::Ok();
}

Status ReadBool(const JsonAt& at, bool* out) {
  const json& v = at.value();
  if (!v.is_boolean())
    return at.Error(std::string("must be true or false, not ") + JsonTypeName(v));
  *out = v.get<bool>();
  return Status::Ok();
}

Status ReadString(const JsonAt& at, StringRule rule, std::string* out) {
  const json& v = at.value();
  if (!v.is_string()) return at.Error(std::string("must be a string, not ") + JsonTypeName(v));
  if (rule == StringRule::kNonEmpty && v.get_ref<const std::string&>().empty())
    return at.Error("must not be empty");
  *out = v.get<std::string>();
  return Status::Ok();
}

Status ReadChoice(const JsonAt& at, const std::vector<std::string>& names, size_t* index) {
  const json& v = at.value();
  if (!v.is_string()) {
    return at.Error("must be one of " + JoinChoices(names) + ", not " + JsonTypeName(v));
  }
  const std::string& s = v.get_ref<const std::string&>();
  const auto it = std::find(names.begin(), names.end(), s);
  if (it == names.end()) return at.Error(Quote(s) + " is not one of " + JoinChoices(names));
  *index = static_cast<size_t>(it - names.begin());
  return Status::Ok();
}

Status ReadFloats(const JsonAt& at, const NumberRange& range, const std::string& names,
                  size_t count, float* out) {
  const json& v = at.value();
  if (!v.is_array() || v.size() != count) {
    return at.Error(
        "must be an array of " + std::to_string(count) + " numbers [" + names + "], not " +
        (v.is_array() ? "an array of " + std::to_string(v.size()) : std::string(JsonTypeName(v))));
  }
  std::vector<float> values(count);
  for (size_t i = 0; i < count; ++i) {
    if (Status s = ReadFloat(at.Element(i), range, &values[i]); !s.ok()) return s;
  }
  std::copy(values.begin(), values.end(), out);
  return Status::Ok();
}

Status ReadFilePath(const JsonAt& at, std::string* out) {
  std::string file;
  if (Status s = ReadString(at, StringRule::kNonEmpty, &file); !s.ok()) return s;
  std::filesystem::path path(file);
  const std::string& directory = at.document().directory;
  if (path.is_relative() && !directory.empty()) path = std::filesystem::path(directory) / path;
  const std::string resolved = path.lexically_normal().string();
  if (!std::filesystem::is_regular_file(resolved)) return at.Error(Quote(resolved) + " not found");
  *out = resolved;
  return Status::Ok();
}

Status ForEachObject(const JsonAt& at, const std::function<Status(const JsonAt&)>& each) {
  const json& v = at.value();
  if (v.is_object()) return each(at);
  if (!v.is_array()) {
    return at.Error(std::string("must be an object or an array of objects, not ") +
                    JsonTypeName(v));
  }
  for (size_t i = 0; i < v.size(); ++i) {
    if (Status s = each(at.Element(i)); !s.ok()) return s;
  }
  return Status::Ok();
}

std::string FormatNumber(double x) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), x);
  std::string text(buffer, result.ptr);
  // "1e+05" -> "1e5", "1e-05" -> "1e-5".
  const size_t e = text.find('e');
  if (e != std::string::npos) {
    std::string mantissa = text.substr(0, e), exponent = text.substr(e + 1);
    const bool negative = !exponent.empty() && exponent[0] == '-';
    if (!exponent.empty() && (exponent[0] == '+' || exponent[0] == '-')) exponent.erase(0, 1);
    exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
    text = mantissa + "e" + (negative ? "-" : "") + exponent;
  }
  return text;
}

json FloatJson(float x) {
  if (!std::isfinite(x)) return json(x);
  char buffer[64];
  const auto written = std::to_chars(buffer, buffer + sizeof(buffer), x);
  double shortest = 0.0;
  std::from_chars(buffer, written.ptr, shortest);
  // The decimal is read as a double, then rounded to float by the reader: keep it only when that
  // gives x back.
  if (static_cast<float>(shortest) != x) shortest = static_cast<double>(x);
  return json(shortest);
}

const char* JsonTypeName(const json& value) {
  if (value.is_null()) return "null";
  if (value.is_boolean()) return "a boolean";
  if (value.is_number()) return "a number";
  if (value.is_string()) return "a string";
  if (value.is_array()) return "an array";
  return "an object";
}

std::string JoinChoices(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : " | ") + name;
  return out;
}

std::string UnknownKeyReason(const std::string& key, const std::string& parent,
                             const std::vector<std::string>& known) {
  const std::vector<std::string> nearest = detail::NearestNames(key, known, 1);
  const std::string suggestion = nearest.empty() ? std::string() : nearest.front();
  return "unknown key: " + key + " is not a parameter of " +
         (parent.empty() ? std::string("the top level") : parent) + " (" +
         (suggestion.empty() ? "" : "did you mean " + suggestion + "? ") +
         "known here: " + JoinChoices(known) + ")";
}

JsonFieldInfo CustomFieldInfo(std::string key, std::string type, std::string what,
                              std::string meaning) {
  JsonFieldInfo info;
  info.key = std::move(key);
  info.range = type;
  info.type = std::move(type);
  info.what = std::move(what);
  info.meaning = std::move(meaning);
  return info;
}

json ReferenceEntry(const JsonFieldInfo& info, const json& default_value) {
  return {{"default", default_value},
          {"unit", info.unit},
          {"range", info.range},
          {"description", info.meaning}};
}

void AppendReferenceSection(const std::string& heading, const std::string& description,
                            const std::vector<JsonReferenceRow>& rows, std::string* out) {
  *out += "### " + heading + "\n\n";
  if (!description.empty()) *out += description + "\n\n";
  *out += "| key | type | default | meaning |\n|---|---|---|---|\n";
  for (const JsonReferenceRow& row : rows) {
    const JsonFieldInfo& info = *row.info;
    std::string type = info.type + (info.unit.empty() ? "" : " " + info.unit);
    std::string default_text = info.required                ? "**required**"
                               : !info.default_text.empty() ? info.default_text
                               : row.nested                 ? "see below"
                                                            : DefaultText(row.default_value);
    *out += "| `" + info.key + "` | " + Cell(type) + " | " + Cell(default_text) + " | " +
            Cell(info.meaning) + " |\n";
  }
  *out += "\n";
}

}  // namespace drape::bake
