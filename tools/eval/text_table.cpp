// Aligned text or markdown tables (tools/eval/text_table.hpp).
#include "tools/eval/text_table.hpp"

#include <algorithm>

namespace uwbnav::eval {

void print_table(std::FILE* f, const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                 bool markdown) {
  std::vector<size_t> w(header.size());
  for (size_t i = 0; i < header.size(); ++i) w[i] = header[i].size();
  for (const auto& r : rows) {
    for (size_t i = 0; i < r.size() && i < w.size(); ++i) w[i] = std::max(w[i], r[i].size());
  }
  const auto line = [&](const std::vector<std::string>& cells) {
    std::string s = markdown ? "|" : "";
    for (size_t i = 0; i < header.size(); ++i) {
      const std::string& c = i < cells.size() ? cells[i] : std::string();
      const std::string pad(w[i] - c.size(), ' ');
      if (markdown) {
        s += " " + (i == 0 ? c + pad : pad + c) + " |";
      } else {
        s += (i == 0 ? c + pad : "  " + pad + c);
      }
    }
    std::fprintf(f, "%s\n", s.c_str());
  };
  line(header);
  if (markdown) {
    std::string sep = "|";
    for (size_t i = 0; i < header.size(); ++i) sep += (i == 0 ? std::string(w[i] + 2, '-') : std::string(w[i] + 1, '-') + ":") + "|";
    std::fprintf(f, "%s\n", sep.c_str());
  } else {
    size_t total = 0;
    for (size_t i = 0; i < w.size(); ++i) total += w[i] + (i == 0 ? 0 : 2);
    std::fprintf(f, "%s\n", std::string(total, '-').c_str());
  }
  for (const auto& r : rows) line(r);
}

}  // namespace uwbnav::eval
