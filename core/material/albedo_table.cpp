// The albedo table's cells as the build integrated them (core/material/albedo_table.h).
#include "core/material/albedo_table.h"

namespace photond::albedo_table {
namespace {

constexpr Cell kCells[kRoughnessCells] = {
#include "albedo_table_cells.inc"
};

}  // namespace

const Cell& cell(int j) { return kCells[j]; }

}  // namespace photond::albedo_table
