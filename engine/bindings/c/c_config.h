// A model's C configuration struct bound to its C++ field table (grove/config_fields.h): one row
// per member, naming the field it holds, and the conversions both ways driven by those rows.
// A field added to a model is one row here (and one member of the C struct).
//
// Thread safety: a binding is immutable once built; any number of threads may convert with it.
#ifndef GROVE_ENGINE_BINDINGS_C_C_CONFIG_H_
#define GROVE_ENGINE_BINDINGS_C_C_CONFIG_H_

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "grove/config_fields.h"
#include "grove/status.h"

namespace grove::capi {

// A member of the C struct CConfig that holds the field `name`.
template <typename CConfig>
struct CMember {
  const char* name;
  bool real;  // a double member (the field is kReal); otherwise an integer (or an enum as int)
  std::function<FieldValue(const CConfig&, FieldType)> get;
  std::function<void(CConfig*, const FieldValue&)> set;
};

template <typename CConfig, typename T>
CMember<CConfig> Member(const char* name, T CConfig::*member) {
  static_assert(std::is_arithmetic_v<T>);
  return {name, std::is_floating_point_v<T>,
          [member](const CConfig& c, FieldType type) -> FieldValue {
            if (type == FieldType::kReal) return static_cast<double>(c.*member);
            if (type == FieldType::kUnsigned) return static_cast<uint64_t>(c.*member);
            return static_cast<int64_t>(c.*member);
          },
          [member](CConfig* c, const FieldValue& v) {
            std::visit([&](auto x) { c->*member = static_cast<T>(x); }, v);
          }};
}

// The row of CConfig's member `m`, which holds the field of the same name.
#define GROVE_C_MEMBER(CConfig, m) ::grove::capi::Member(#m, &CConfig::m)

// The rows of the filter's fields (grove/filter_config.h), which every model's C struct holds
// under the same names.
template <typename CConfig>
std::vector<CMember<CConfig>> FilterMembers() {
  using C = CConfig;
  return {GROVE_C_MEMBER(C, particles),  GROVE_C_MEMBER(C, seed),
          GROVE_C_MEMBER(C, resampling), GROVE_C_MEMBER(C, resample_threshold),
          GROVE_C_MEMBER(C, threads),    GROVE_C_MEMBER(C, batch)};
}

// The rows of island mode's fields.
template <typename CConfig>
std::vector<CMember<CConfig>> IslandMembers() {
  using C = CConfig;
  return {GROVE_C_MEMBER(C, islands), GROVE_C_MEMBER(C, island_exchange_steps),
          GROVE_C_MEMBER(C, island_exchange_fraction)};
}

// A C++ configuration Config (its table `fields`) and its C struct CConfig (`members`).
template <typename Config, typename CConfig>
class ConfigBinding {
 public:
  using CppConfig = Config;
  using CStruct = CConfig;

  ConfigBinding(const std::vector<ConfigField<Config>>& fields,
                const std::vector<std::vector<CMember<CConfig>>>& member_groups)
      : fields_(fields) {
    for (const auto& group : member_groups) {
      for (const CMember<CConfig>& m : group) {
        const ConfigField<Config>* f = FindField(fields, m.name);
        if (f == nullptr) {
          Broken(std::string("the C member ") + m.name + " names no field");
        } else if (m.real != (f->info.type == FieldType::kReal)) {
          Broken(std::string("the C member ") + m.name + " is not of its field's type");
        } else {
          rows_.push_back({f, m});
        }
      }
    }
    for (const ConfigField<Config>& f : fields) {
      int rows = 0;
      for (const Row& r : rows_) rows += r.field == &f ? 1 : 0;
      if (rows != 1) Broken(std::string("field ") + f.info.name + " has no one C member");
    }
  }

  // Internal naming the first broken row (a bug of the binding, caught by the C test).
  const Status& status() const { return status_; }

  Config ToCpp(const CConfig& c) const {
    Config out;
    for (const Row& r : rows_) r.field->set(&out, r.member.get(c, r.field->info.type));
    return out;
  }
  CConfig ToC(const Config& c) const {
    CConfig out{};
    for (const Row& r : rows_) r.member.set(&out, r.field->get(c));
    return out;
  }
  const std::vector<ConfigField<Config>>& fields() const { return fields_; }

 private:
  struct Row {
    const ConfigField<Config>* field;
    CMember<CConfig> member;
  };
  void Broken(const std::string& what) {
    if (status_.ok()) status_ = InternalError("C configuration binding: " + what);
  }

  const std::vector<ConfigField<Config>>& fields_;
  std::vector<Row> rows_;
  Status status_;
};

// The binding of Config's table `fields` to CConfig's members (members() -> their groups),
// built on first use and never destroyed: a call may come during static destruction.
template <typename Config, typename CConfig, typename Members>
const ConfigBinding<Config, CConfig>& BindOnce(const std::vector<ConfigField<Config>>& fields,
                                               Members members) {
  static const auto* binding = new ConfigBinding<Config, CConfig>(fields, members());
  return *binding;
}

}  // namespace grove::capi

#endif  // GROVE_ENGINE_BINDINGS_C_C_CONFIG_H_
