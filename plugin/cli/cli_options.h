// CLI11 checks built from libspecula's one table of option ranges (core/api/specula.h option_rules), so the CLI, the
// C++ API, the C ABI and the Python module accept exactly the same values (issue 35); a value outside is exit 2.
#pragma once

#include "core/api/specula.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <string>

namespace specula {

// A validator for an option whose rule is 'rule': numbers only, NaN and infinities refused, the message the API gives.
inline CLI::Validator optionCheck(const OptionRule& rule) {
    return CLI::Validator(
        [rule](std::string& text) -> std::string {
            try {
                size_t used = 0;
                const double v = std::stod(text, &used);
                if (used != text.size()) return std::string(rule.name) + " expects a number, got '" + text + "'";
                if (!rule.contains(v))  // CLI11 puts the option's name in front
                    return "value " + text + " is outside " + CLI::detail::to_string(rule.min) + ".." + CLI::detail::to_string(rule.max);
            } catch (const std::exception&) {
                return std::string(rule.name) + " expects a number, got '" + text + "'";
            }
            return std::string();
        },
        "NUMBER in [" + CLI::detail::to_string(rule.min) + " - " + CLI::detail::to_string(rule.max) + "]");
}

}  // namespace specula
