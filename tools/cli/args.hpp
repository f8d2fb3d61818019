// Minimal command-line parsing for `uwbnav` subcommands: positionals and
// --key value / --flag options, with clear one-line errors.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "firmware/param_text.hpp"

namespace uwbnav::cli {

class Args {
 public:
  // `flags` are options without a value; every other --option takes one value.
  // --help is always a flag (unknown to every command: the command prints its usage,
  // and main turns `uwbnav CMD --help` into exit 0 with the usage on stdout).
  Args(int argc, char** argv, const std::vector<std::string>& flags) {
    for (int i = 1; i < argc; ++i) {
      std::string a = argv[i];
      if (a.rfind("--", 0) == 0) {
        const bool is_flag = a == "--help" || std::find(flags.begin(), flags.end(), a) != flags.end();
        if (is_flag) {
          options_[a].push_back("1");
        } else if (i + 1 < argc) {
          options_[a].push_back(argv[++i]);
        } else {
          error_ = "option " + a + " needs a value";
        }
      } else {
        positional_.push_back(a);
      }
    }
  }
  const std::string& error() const { return error_; }
  const std::vector<std::string>& positional() const { return positional_; }
  bool has(const std::string& key) const { return options_.count(key) > 0; }
  std::string get(const std::string& key, const std::string& def = "") const {
    auto it = options_.find(key);
    return it == options_.end() ? def : it->second.back();
  }
  std::vector<std::string> all(const std::string& key) const {
    auto it = options_.find(key);
    return it == options_.end() ? std::vector<std::string>{} : it->second;
  }
  // Unknown options (not in `known`): returns the first, or "".
  std::string unknown(const std::vector<std::string>& known) const {
    for (const auto& kv : options_) {
      if (std::find(known.begin(), known.end(), kv.first) == known.end()) return kv.first;
    }
    return "";
  }
  bool get_u64(const std::string& key, uint64_t def, uint64_t* out) const {
    if (!has(key)) {
      *out = def;
      return true;
    }
    const std::string v = get(key);
    char* end = nullptr;
    const unsigned long long x = std::strtoull(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0' || v[0] == '-') return false;
    *out = x;
    return true;
  }

 private:
  std::vector<std::string> positional_;
  std::map<std::string, std::vector<std::string>> options_;
  std::string error_;
};

// "NAME=VALUE" (command-line form) through parse_param_value; a text without
// '=' or without a name gives "'TEXT' is not NAME=VALUE".
inline Status parse_param_assignment(const std::string& text, const ParamDef** def, float* value, char* msg,
                                     size_t cap) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    std::snprintf(msg, cap, "'%s' is not NAME=VALUE", text.c_str());
    return Status::kInvalidArgument;
  }
  return parse_param_value(text.substr(0, eq).c_str(), text.c_str() + eq + 1, def, value, msg, cap);
}

// Parses every --param NAME=VALUE of `args` (after the table: bounds, whole-number
// kinds). On the first bad one prints "PROG: param: <reason>" (the console's
// wording, firmware/param_text.hpp) and returns false.
inline bool parse_param_options(const Args& args, const char* prog, std::vector<std::pair<std::string, float>>* out) {
  for (const auto& text : args.all("--param")) {
    const ParamDef* def = nullptr;
    float value = 0.0F;
    char why[kParamErrorMax];
    if (!ok(parse_param_assignment(text, &def, &value, why, sizeof why))) {
      std::fprintf(stderr, "%s: param: %s\n", prog, why);
      return false;
    }
    out->emplace_back(def->name, value);
  }
  return true;
}

}  // namespace uwbnav::cli
