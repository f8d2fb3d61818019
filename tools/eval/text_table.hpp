// Aligned text or markdown tables of the evaluation commands (eval family,
// eval outage): first column left-aligned, the others right-aligned.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace uwbnav::eval {

void print_table(std::FILE* f, const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                 bool markdown);

}  // namespace uwbnav::eval
