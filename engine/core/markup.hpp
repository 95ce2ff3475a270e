#pragma once
// Text for XML and HTML: the five markup characters escaped; invalid UTF-8 and the characters
// XML 1.0 cannot carry (most C0 controls, U+FFFE/U+FFFF) replaced by U+FFFD, so a file stays
// well-formed whatever was typed as a trainee name. Used by the records' XML export and the HTML
// report.
#include <string>
#include <string_view>

namespace phaco {

void append_escaped_markup(std::string& out, std::string_view s);
std::string escape_markup(std::string_view s);

}  // namespace phaco
