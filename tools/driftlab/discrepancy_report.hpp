// report.html of `driftlab discrepancy` (html_report.hpp): plots of the residual views
// (models/discrepancy/views.hpp) before the first and after the last named effect, beside
// report.json's data (models/discrepancy/report.hpp). Rates are shown in deg/h.
#pragma once

#include <string>

#include "models/discrepancy/report.hpp"

namespace driftlab::cli {

std::string discrepancy_html(const discrepancy::Result& result, const discrepancy::ReportInfo& info);

}  // namespace driftlab::cli
