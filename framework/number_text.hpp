// A number as tables and reports write it (HTML tables, report.json's sentences): integers in
// full, else `digits` significant digits (C locale), non-finite values as "–". Messages use
// message_number (error.hpp).
#pragma once

#include <string>

namespace driftlab {

std::string format_number(double v, int digits = 4);

}  // namespace driftlab
