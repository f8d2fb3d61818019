// Parameter assignments from text: strict decimal parse, table lookup, bounds and
// kind checks, with the one wording shared by the console and the CLI.
#include "firmware/param_text.hpp"

#include <cstdio>
#include <cstring>

#include "firmware/text_format.hpp"

namespace uwbnav {

constexpr int kParamDigits = 6;  // significant digits of values in the texts ("%g", as the console)

Status check_param_value(const char* name, float value, const ParamDef** def, char* msg, size_t cap) {
  if (cap > 0) msg[0] = '\0';
  const ParamDef* d = Params::find(name);
  if (d == nullptr) {
    std::snprintf(msg, cap, "unknown parameter '%s' (see param list)", name);
    return Status::kNotFound;
  }
  char v_text[kGeneralTextMax];
  (void)format_general(v_text, sizeof v_text, value, kParamDigits);
  if (!(value >= d->min && value <= d->max)) {
    char lo[kGeneralTextMax];
    char hi[kGeneralTextMax];
    (void)format_general(lo, sizeof lo, d->min, kParamDigits);
    (void)format_general(hi, sizeof hi, d->max, kParamDigits);
    std::snprintf(msg, cap, "%s=%s out of range [%s, %s]", d->name, v_text, lo, hi);
    return Status::kOutOfRange;
  }
  if (d->kind != ParamKind::kReal && !detail::is_whole(value)) {
    std::snprintf(msg, cap, "%s=%s is not a whole number (%s parameter)", d->name, v_text,
                  param_kind_name(d->kind));
    return Status::kInvalidArgument;
  }
  *def = d;
  return Status::kOk;
}

Status parse_param_value(const char* name, const char* value_text, const ParamDef** def, float* value, char* msg,
                         size_t cap) {
  if (cap > 0) msg[0] = '\0';
  const ParamDef* d = Params::find(name);
  const Result<float> parsed = parse_decimal_float(value_text);
  if (d != nullptr && !parsed.ok()) {
    std::snprintf(msg, cap, "%s=%s is not a finite number", d->name, value_text);
    return Status::kInvalidArgument;
  }
  const Status s = check_param_value(name, parsed.ok() ? parsed.value() : 0.0F, def, msg, cap);
  if (ok(s)) *value = parsed.value();
  return s;
}

Status parse_param_assignment(const char* text, const ParamDef** def, float* value, char* msg, size_t cap) {
  const char* eq = std::strchr(text, '=');
  char name[64];
  const size_t name_len = eq == nullptr ? 0 : static_cast<size_t>(eq - text);
  if (eq == nullptr || name_len == 0 || name_len >= sizeof name) {
    std::snprintf(msg, cap, "'%s' is not NAME=VALUE", text);
    return Status::kInvalidArgument;
  }
  std::memcpy(name, text, name_len);
  name[name_len] = '\0';
  return parse_param_value(name, eq + 1, def, value, msg, cap);
}

}  // namespace uwbnav
