// A number as tables and reports write it (HTML tables, report.json's sentences): integers in
// full, else `digits` significant digits (C locale), non-finite values as "–". Messages use
// message_number (error.hpp). number_text: a number in a fixed printf format of one double ("%.3g"),
// for the columns of text tables.
#pragma once

#include <string>

namespace driftlab {

std::string format_number(double v, int digits = 4);
std::string number_text(double v, const char* printf_format);

}  // namespace driftlab
