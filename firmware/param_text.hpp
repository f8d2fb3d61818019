// Parameter values from text (console `param set NAME VALUE`, CLI --param NAME=VALUE
// through tools/cli/args.hpp):
// one parser and one wording for every refusal, so every entry point names the
// parameter and the reason the same way.
#pragma once

#include <cstddef>

#include "estimator/params.hpp"

namespace uwbnav {

constexpr size_t kParamErrorMax = 128;  // longest refusal text, terminator included

// Checks NAME and VALUE text against the parameter table without changing anything.
// kOk: *def and *value are set. Otherwise `msg` (cap bytes) holds the reason,
// starting with the parameter's name:
//   "unknown parameter 'NAME' (see param list)"
//   "NAME=TEXT is not a finite number"
//   "NAME=VALUE out of range [MIN, MAX]"
//   "NAME=VALUE is not a whole number (KIND parameter)"
[[nodiscard]] Status parse_param_value(const char* name, const char* value_text, const ParamDef** def, float* value,
                                       char* msg, size_t cap);

// The checks of parse_param_value on a number (value NaN: out of range).
[[nodiscard]] Status check_param_value(const char* name, float value, const ParamDef** def, char* msg, size_t cap);

}  // namespace uwbnav
