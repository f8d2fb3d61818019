// Parameter values from text: strict decimal parse, table lookup, bounds and
// kind checks, with the one wording shared by the console and the CLI.
#include "firmware/param_text.hpp"

#include <cstdarg>
#include <cstdio>

#include "firmware/text_format.hpp"

namespace uwbnav {
namespace {

constexpr int kParamDigits = 6;  // significant digits of values in the texts ("%g", as the console)

// Names by ParamKind value (an array: smaller than param_kind_name's switch on the M4F).
constexpr const char* kKindNames[] = {"real", "integer", "bool", "enum"};

// printf into msg through vsnprintf (which the console links anyway).
__attribute__((format(printf, 3, 4))) void say(char* msg, size_t cap, const char* fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  (void)std::vsnprintf(msg, cap, fmt, ap);
  va_end(ap);
}

}  // namespace

Status check_param_value(const char* name, float value, const ParamDef** def, char* msg, size_t cap) {
  const ParamDef* d = Params::find(name);
  if (d == nullptr) {
    say(msg, cap, "unknown parameter '%s' (see param list)", name);
    return Status::kNotFound;
  }
  const bool in_range = value >= d->min && value <= d->max;
  if (in_range && (d->kind == ParamKind::kReal || detail::is_whole(value))) {
    *def = d;
    return Status::kOk;
  }
  char v[kGeneralTextMax];
  char lo[kGeneralTextMax];
  char hi[kGeneralTextMax];
  (void)format_general(v, sizeof v, value, kParamDigits);
  (void)format_general(lo, sizeof lo, d->min, kParamDigits);
  (void)format_general(hi, sizeof hi, d->max, kParamDigits);
  if (!in_range) {
    say(msg, cap, "%s=%s out of range [%s, %s]", d->name, v, lo, hi);
    return Status::kOutOfRange;
  }
  say(msg, cap, "%s=%s is not a whole number (%s parameter)", d->name, v,
      kKindNames[static_cast<size_t>(d->kind) & 3U]);
  return Status::kInvalidArgument;
}

Status parse_param_value(const char* name, const char* value_text, const ParamDef** def, float* value, char* msg,
                         size_t cap) {
  const Result<float> parsed = parse_decimal_float(value_text);
  if (!parsed.ok() && Params::find(name) != nullptr) {
    say(msg, cap, "%s=%s is not a finite number", name, value_text);
    return Status::kInvalidArgument;
  }
  const Status s = check_param_value(name, parsed.ok() ? parsed.value() : 0.0F, def, msg, cap);
  if (ok(s)) *value = parsed.value();
  return s;
}

}  // namespace uwbnav
