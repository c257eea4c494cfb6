#include "common/yaml_reader.h"

#include <optional>

#include "common/error.h"
#include "common/yaml_file.h"

namespace hgrasp::yaml {

std::string Reader::Where(const YAML::Mark& mark) const { return yaml::Where(path_, mark); }

void Reader::Fail(const YAML::Mark& mark, const std::string& field, const std::string& value,
                  const std::string& expected) const {
  throw InputError(Where(mark), field, value, expected);
}

void Reader::Fail(const YAML::Node& at, const std::string& field,
                  const std::string& expected) const {
  Fail(at.Mark(), field, Render(at), expected);
}

Entries Reader::MapOf(const YAML::Node& n, const std::string& field, const Keys& allowed,
                      const std::string& expected) const {
  if (!n.IsMap()) Fail(n, field.empty() ? "top level" : field, expected);
  Entries entries;
  for (const auto& kv : n) {
    const YAML::Node& key = kv.first;
    const std::string name = key.IsScalar() ? key.Scalar() : Render(key);
    bool known = false;
    for (std::string_view a : allowed) known = known || name == a;
    if (!key.IsScalar() || !known) {
      Fail(key.Mark(), Join(field, name), name, "a known key here, " + OneOf(allowed));
    }
    if (entries.count(name) != 0) {
      Fail(key.Mark(), Join(field, name), name,
           "each key once (it is also on line " +
               std::to_string(entries.at(name).key.Mark().line + 1) + ")");
    }
    entries.emplace(name, Entry{key, kv.second});
  }
  return entries;
}

const YAML::Node* Reader::Find(const Entries& entries, std::string_view key) {
  const auto it = entries.find(std::string(key));
  return it == entries.end() ? nullptr : &it->second.value;
}

const YAML::Node& Reader::Require(const Entries& entries, const YAML::Node& map,
                                  const std::string& field, std::string_view key,
                                  const std::string& expected) const {
  const YAML::Node* n = Find(entries, key);
  if (n == nullptr) Fail(map.Mark(), Join(field, key), "", expected);
  return *n;
}

double Reader::Number(const YAML::Node& n, const std::string& field,
                      const std::string& expected) const {
  const std::optional<double> v = ParseNumber(n);
  if (!v) Fail(n, field, expected + QuoteHint(n));
  return *v;
}

Eigen::VectorXd Reader::Numbers(const YAML::Node& n, const std::string& field, std::size_t count,
                                const std::string& expected) const {
  if (!n.IsSequence() || n.size() != count) Fail(n, field, expected);
  Eigen::VectorXd v(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::optional<double> x = ParseNumber(n[i]);
    if (!x) Fail(n, field, expected + QuoteHint(n));
    v[static_cast<Eigen::Index>(i)] = *x;
  }
  return v;
}

std::string Reader::Text(const YAML::Node& n, const std::string& field,
                         const std::string& expected) const {
  if (!n.IsScalar() || n.Scalar().empty()) Fail(n, field, expected);
  return n.Scalar();
}

}  // namespace hgrasp::yaml
