#pragma once
// One schema mechanism for drape's JSON inputs: the bake config (drape-bake --config, a scene's
// /bake) and the scene (drape-sim). A JsonSchema<T> is the table of one JSON object's fields:
// key, type, unit, range, default, one-line meaning and the setter into the C++ struct T.
// Read() refuses an unknown key (naming its JSON path and the keys known there), a value of the
// wrong type or out of its range, a missing required field, then runs the object's cross-field
// rules; every refusal is one line, "<file>: <JSON path>: <reason>". The same tables print the
// references (drape-bake --dump-config, docs/SCENES.md), so a reference cannot drift from the code.

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape::bake {

// Where JSON values come from: the name that starts every message, and the directory relative
// file paths resolve against.
struct JsonDocument {
  std::string source;
  std::string directory;
};

// A JSON value at its path in a document: "" is the root, "/garments/0/attach".
class JsonAt {
 public:
  JsonAt(const nlohmann::json& value, std::string path, const JsonDocument& document)
      : value_(&value), path_(std::move(path)), document_(&document) {}

  const nlohmann::json& value() const { return *value_; }
  const std::string& path() const { return path_; }
  const JsonDocument& document() const { return *document_; }

  // The member `key` of this object; null (with its path) when absent.
  JsonAt Member(const std::string& key) const;
  JsonAt Element(size_t index) const;
  // The member `key`, or nullptr when this is not an object or has no such member.
  const nlohmann::json* Find(const std::string& key) const;
  // kInvalidArgument "<source>: <path>: <reason>" (the root's path reads "/").
  Status Error(const std::string& reason) const;

 private:
  const nlohmann::json* value_;
  std::string path_;
  const JsonDocument* document_;
};

// An interval of numbers; either end may be open.
struct NumberRange {
  double lo = 0.0, hi = 0.0;
  bool lo_open = false, hi_open = false;
  std::string Text() const;  // "[0, 0.1]", "(0, 100]"
};
inline NumberRange Closed(double lo, double hi) { return {lo, hi, false, false}; }
inline NumberRange OpenBelow(double lo, double hi) { return {lo, hi, true, false}; }

enum class StringRule : uint8_t { kAny, kNonEmpty };

// Readers of one value: each writes *out only when the value is accepted.
Status ReadDouble(const JsonAt& at, const NumberRange& range, double* out);
// Checked after rounding to float, as stored: a value at a bound (0.1) becomes the float nearest
// to it (0.100000001), and that stored value must pass again when written out and read back.
Status ReadFloat(const JsonAt& at, const NumberRange& range, float* out);
Status ReadUnsigned(const JsonAt& at, uint64_t lo, uint64_t hi, uint64_t* out);
Status ReadBool(const JsonAt& at, bool* out);
Status ReadString(const JsonAt& at, StringRule rule, std::string* out);
// A string that must be one of `names`; *index gets its position.
Status ReadChoice(const JsonAt& at, const std::vector<std::string>& names, size_t* index);
// An array of `count` numbers in `range`, named in messages by `names` ("x, y, z").
Status ReadFloats(const JsonAt& at, const NumberRange& range, const std::string& names,
                  size_t count, float* out);
// A non-empty file name, resolved against the document's directory; it must name a regular file.
Status ReadFilePath(const JsonAt& at, std::string* out);
// An object, or an array of objects: `each` for every one of them (any other value is refused).
Status ForEachObject(const JsonAt& at, const std::function<Status(const JsonAt&)>& each);

// Shortest text that reads back as x; exponents without '+' or leading zeros ("1e5", "0.005").
std::string FormatNumber(double x);
// The shortest decimal that reads back as x, as a JSON number ("0.005", not 0.004999999888).
nlohmann::json FloatJson(float x);
// "null", "a boolean", "a number", "a string", "an array" or "an object".
const char* JsonTypeName(const nlohmann::json& value);
// "a | b | c"
std::string JoinChoices(const std::vector<std::string>& names);

// How the references and the messages describe a field.
struct JsonFieldInfo {
  std::string key;
  std::string type;     // in the scene reference, e.g. "number [0, 1]", "`rest` \| `bind`"
  std::string range;    // in --dump-config: "[0, 1]", "a | b", "true | false", "any string"
  std::string what;     // in messages: "a number in [0, 1]", "one of a | b", "true or false"
  std::string unit;     // "m", "s", "Hz", ... or empty
  std::string meaning;  // one line
  bool required = false;
  std::string default_text;  // as the scene reference shows it; empty: from the default value
};

// The description of a field read by its own code (JsonSchema::Custom): `type` is shown in the
// references, `what` in messages ("must be <what>", "missing (required: <what>)").
JsonFieldInfo CustomFieldInfo(std::string key, std::string type, std::string what,
                              std::string meaning);

// A row of a reference table: the field and its default as JSON (null when the field has none).
struct JsonReferenceRow {
  const JsonFieldInfo* info;
  nlohmann::json default_value;
  bool nested = false;  // an object described in a section of its own
};

// The reason for an unknown key `key` in the object at `parent`, which knows `known`.
std::string UnknownKeyReason(const std::string& key, const std::string& parent,
                             const std::vector<std::string>& known);
// {"default", "unit", "range", "description"} of a field.
nlohmann::json ReferenceEntry(const JsonFieldInfo& info, const nlohmann::json& default_value);
// A markdown section: "### <heading>", the description, and the table | key | type | default |
// meaning |.
void AppendReferenceSection(const std::string& heading, const std::string& description,
                            const std::vector<JsonReferenceRow>& rows, std::string* out);

template <class T>
class JsonSchema {
 public:
  template <class V>
  using Access = std::function<V&(T&)>;
  using Reader = std::function<Status(const JsonAt&, T&)>;
  using ValueOf = std::function<nlohmann::json(const T&)>;
  // Writes the reference sections of a nested object: (defaults of T, the field's path, out).
  using Sections = std::function<void(const T&, const std::string&, std::string*)>;

  explicit JsonSchema(std::string description = "") : description_(std::move(description)) {}

  JsonSchema& Number(std::string key, std::string unit, NumberRange range, std::string meaning,
                     Access<double> field) {
    return Add(
        NumberInfo(std::move(key), "number", std::move(unit), range, std::move(meaning)),
        [field, range](const JsonAt& at, T& t) {
          double x = 0.0;
          if (Status s = ReadDouble(at, range, &x); !s.ok()) return s;
          field(t) = x;
          return Status::Ok();
        },
        ValueFrom(field));
  }

  JsonSchema& Float(std::string key, std::string unit, NumberRange range, std::string meaning,
                    Access<float> field) {
    return Add(
        NumberInfo(std::move(key), "number", std::move(unit), range, std::move(meaning)),
        [field, range](const JsonAt& at, T& t) { return ReadFloat(at, range, &field(t)); },
        [field](const T& t) { return FloatJson(field(const_cast<T&>(t))); });
  }

  // An unsigned count in a field of type UInt.
  template <class UInt>
  JsonSchema& Unsigned(std::string key, std::string unit, std::type_identity_t<UInt> lo,
                       std::type_identity_t<UInt> hi, std::string meaning, Access<UInt> field) {
    static_assert(std::is_unsigned_v<UInt>);
    const NumberRange range = Closed(static_cast<double>(lo), static_cast<double>(hi));
    JsonFieldInfo info =
        NumberInfo(std::move(key), "integer", std::move(unit), range, std::move(meaning));
    info.range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    info.type = "integer " + info.range;
    info.what = "an integer in " + info.range;
    return Add(
        std::move(info),
        [field, lo, hi](const JsonAt& at, T& t) {
          uint64_t x = 0;
          if (Status s = ReadUnsigned(at, lo, hi, &x); !s.ok()) return s;
          field(t) = static_cast<UInt>(x);
          return Status::Ok();
        },
        ValueFrom(field));
  }

  JsonSchema& Bool(std::string key, std::string meaning, Access<bool> field) {
    return Add(
        Info(std::move(key), "bool", "true | false", "true or false", "", std::move(meaning)),
        [field](const JsonAt& at, T& t) { return ReadBool(at, &field(t)); }, ValueFrom(field));
  }

  JsonSchema& String(std::string key, StringRule rule, std::string meaning,
                     Access<std::string> field) {
    return Add(
        Info(std::move(key), "string", rule == StringRule::kAny ? "any string" : "a name",
             rule == StringRule::kAny ? "a string" : "a non-empty string", "", std::move(meaning)),
        [field, rule](const JsonAt& at, T& t) { return ReadString(at, rule, &field(t)); },
        ValueFrom(field));
  }

  // A string that must be one of `names`, kept as given.
  JsonSchema& Choice(std::string key, std::vector<std::string> names, std::string meaning,
                     Access<std::string> field) {
    return Add(
        ChoiceInfo(std::move(key), names, std::move(meaning)),
        [field, names](const JsonAt& at, T& t) {
          size_t index = 0;
          if (Status s = ReadChoice(at, names, &index); !s.ok()) return s;
          field(t) = names[index];
          return Status::Ok();
        },
        ValueFrom(field));
  }

  // A string naming a value of the enum E.
  template <class E>
  JsonSchema& Enum(std::string key, std::vector<std::pair<std::string, E>> choices,
                   std::string meaning, Access<E> field) {
    std::vector<std::string> names;
    for (const auto& choice : choices) names.push_back(choice.first);
    return Add(
        ChoiceInfo(std::move(key), names, std::move(meaning)),
        [field, names, choices](const JsonAt& at, T& t) {
          size_t index = 0;
          if (Status s = ReadChoice(at, names, &index); !s.ok()) return s;
          field(t) = choices[index].second;
          return Status::Ok();
        },
        [field, choices](const T& t) {
          const E value = field(const_cast<T&>(t));
          for (const auto& [name, v] : choices) {
            if (v == value) return nlohmann::json(name);
          }
          return nlohmann::json(nullptr);
        });
  }

  // [x, y, z], each coordinate in [-limit, limit].
  JsonSchema& Vector(std::string key, std::string unit, double limit, std::string meaning,
                     Access<Float3> field) {
    return Add(
        VectorInfo(std::move(key), std::move(unit), std::move(meaning)),
        [field, limit](const JsonAt& at, T& t) {
          float c[3];
          if (Status s = ReadFloats(at, Closed(-limit, limit), "x, y, z", 3, c); !s.ok()) return s;
          field(t) = {c[0], c[1], c[2]};
          return Status::Ok();
        },
        [field](const T& t) {
          const Float3 v = field(const_cast<T&>(t));
          return nlohmann::json::array({FloatJson(v.x), FloatJson(v.y), FloatJson(v.z)});
        });
  }

  // A file name relative to the document; stored resolved.
  JsonSchema& FilePath(std::string key, std::string meaning, Access<std::string> field) {
    return Add(
        Info(std::move(key), "string", "a file name", "a file name", "", std::move(meaning)),
        [field](const JsonAt& at, T& t) { return ReadFilePath(at, &field(t)); }, nullptr);
  }

  // A nested object described by `schema`, read into field(t).
  template <class U>
  JsonSchema& Object(std::string key, const JsonSchema<U>& schema, std::string meaning,
                     std::type_identity_t<std::function<U&(T&)>> field) {
    const JsonSchema<U>* nested = &schema;  // schemas are static tables
    JsonField& added =
        Add(
            Info(std::move(key), "object", "an object", "an object", "", std::move(meaning)),
            [nested, field](const JsonAt& at, T& t) { return nested->Read(at, &field(t)); },
            [nested, field](const T& t) { return nested->ToJson(field(const_cast<T&>(t))); })
            .fields_.back();
    added.reference = [nested, field](const T& t) {
      return nested->Reference(field(const_cast<T&>(t)));
    };
    added.sections = [nested, field](const T& t, const std::string& path, std::string* out) {
      nested->WriteSections(field(const_cast<T&>(t)), path, "`" + path + "`", out);
    };
    return *this;
  }

  // A field with its own reader: `value` gives its value for the references (may be null),
  // `sections` writes the reference sections of the objects it holds (may be null).
  JsonSchema& Custom(JsonFieldInfo info, Reader read, ValueOf value = nullptr,
                     Sections sections = nullptr) {
    Add(std::move(info), std::move(read), std::move(value));
    fields_.back().sections = std::move(sections);
    return *this;
  }

  // The field added last must be present.
  JsonSchema& Required() {
    fields_.back().info.required = true;
    return *this;
  }
  // The default of the field added last, as the scene reference shows it.
  JsonSchema& Default(std::string text) {
    fields_.back().info.default_text = std::move(text);
    return *this;
  }
  // A cross-field rule, run on the object after every field was read.
  JsonSchema& Rule(Reader rule) {
    rules_.push_back(std::move(rule));
    return *this;
  }

  // Reads the object at `at` into *out: unknown keys, then the fields in table order, then the
  // rules. On error *out may be partly written: read into a copy that is dropped on failure.
  Status Read(const JsonAt& at, T* out) const {
    const nlohmann::json& object = at.value();
    if (!object.is_object())
      return at.Error(std::string("must be an object, not ") + JsonTypeName(object));
    for (const auto& item : object.items()) {
      if (Find(item.key()) == nullptr)
        return at.Member(item.key()).Error(UnknownKeyReason(item.key(), at.path(), Keys()));
    }
    for (const JsonField& field : fields_) {
      const JsonAt member = at.Member(field.info.key);
      if (at.Find(field.info.key) == nullptr) {
        if (field.info.required) return member.Error("missing (required: " + field.info.what + ")");
        continue;
      }
      if (Status s = field.read(member, *out); !s.ok()) return s;
    }
    for (const Reader& rule : rules_) {
      if (Status s = rule(at, *out); !s.ok()) return s;
    }
    return Status::Ok();
  }

  // The values of `value`, as a JSON file spells them (nested objects as objects).
  nlohmann::json ToJson(const T& value) const {
    nlohmann::json out = nlohmann::json::object();
    for (const JsonField& field : fields_) {
      if (field.value) out[field.info.key] = field.value(value);
    }
    return out;
  }

  // {key: {"default", "unit", "range", "description"}, object key: {...}}, defaults from
  // `defaults`.
  nlohmann::json Reference(const T& defaults) const {
    nlohmann::json out = nlohmann::json::object();
    for (const JsonField& field : fields_) {
      out[field.info.key] = field.reference
                                ? field.reference(defaults)
                                : ReferenceEntry(field.info, field.value ? field.value(defaults)
                                                                         : nlohmann::json(nullptr));
    }
    return out;
  }

  // The markdown reference: this object's section, then the sections of the objects it holds.
  void WriteSections(const T& defaults, const std::string& path, const std::string& heading,
                     std::string* out) const {
    std::vector<JsonReferenceRow> rows;
    for (const JsonField& field : fields_) {
      rows.push_back({&field.info,
                      field.value && !field.sections ? field.value(defaults) : nlohmann::json(),
                      static_cast<bool>(field.sections)});
    }
    AppendReferenceSection(heading, description_, rows, out);
    for (const JsonField& field : fields_) {
      if (field.sections) field.sections(defaults, path + "/" + field.info.key, out);
    }
  }

 private:
  struct JsonField {
    JsonFieldInfo info;
    Reader read;
    ValueOf value;
    ValueOf reference;  // nested objects: their Reference()
    Sections sections;
  };

  template <class V>
  static ValueOf ValueFrom(Access<V> field) {
    return [field](const T& t) { return nlohmann::json(field(const_cast<T&>(t))); };
  }
  static JsonFieldInfo Info(std::string key, std::string type, std::string range, std::string what,
                            std::string unit, std::string meaning) {
    JsonFieldInfo info;
    info.key = std::move(key);
    info.type = std::move(type);
    info.range = std::move(range);
    info.what = std::move(what);
    info.unit = std::move(unit);
    info.meaning = std::move(meaning);
    return info;
  }
  static JsonFieldInfo NumberInfo(std::string key, const std::string& kind, std::string unit,
                                  const NumberRange& range, std::string meaning) {
    const std::string text = range.Text();
    return Info(std::move(key), kind + " " + text, text,
                (kind == "integer" ? "an integer in " : "a number in ") + text, std::move(unit),
                std::move(meaning));
  }
  static JsonFieldInfo ChoiceInfo(std::string key, const std::vector<std::string>& names,
                                  std::string meaning) {
    std::string type;
    for (const std::string& name : names) type += (type.empty() ? "`" : " \\| `") + name + "`";
    return Info(std::move(key), type, JoinChoices(names), "one of " + JoinChoices(names), "",
                std::move(meaning));
  }
  static JsonFieldInfo VectorInfo(std::string key, std::string unit, std::string meaning) {
    return Info(std::move(key), "[x, y, z]", "[x, y, z]", "an array of 3 numbers [x, y, z]",
                std::move(unit), std::move(meaning));
  }

  JsonSchema& Add(JsonFieldInfo info, Reader read, ValueOf value) {
    fields_.push_back({std::move(info), std::move(read), std::move(value), nullptr, nullptr});
    return *this;
  }
  const JsonField* Find(const std::string& key) const {
    for (const JsonField& field : fields_) {
      if (field.info.key == key) return &field;
    }
    return nullptr;
  }
  std::vector<std::string> Keys() const {
    std::vector<std::string> keys;
    for (const JsonField& field : fields_) keys.push_back(field.info.key);
    return keys;
  }

  template <class>
  friend class JsonSchema;

  std::string description_;
  std::vector<JsonField> fields_;
  std::vector<Reader> rules_;
};

}  // namespace drape::bake
