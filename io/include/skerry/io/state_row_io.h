#pragma once
/// \file
/// Row-level text I/O shared by the files that carry poses and states (TUM, truth_states.csv,
/// states.csv, EuRoC ground truth).
///
/// Quaternions read from files must have a norm within kQuaternionNormTolerance of one (anything
/// else is a mis-ordered or corrupt row); accepted values are normalised.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "skerry/core/nav_state.h"
#include "skerry/io/csv_reader.h"

namespace skerry {

/// Tolerance on | |q| - 1 | for quaternions read from files.
constexpr double kQuaternionNormTolerance = 1e-3;

/// True if | |q| - 1 | < kQuaternionNormTolerance.
bool IsUnitQuaternion(const Eigen::Quaterniond& q);

/// Reads a quaternion stored as x, y, z, w in columns first_col .. first_col+3 of the current
/// row and returns it normalised. Throws InputError (field: the w column) if it is not unit.
Eigen::Quaterniond ReadUnitQuaternion(const CsvReader& reader, int first_col);

/// As ReadUnitQuaternion, for w, x, y, z order (EuRoC). Field on error: the w column.
Eigen::Quaterniond ReadUnitQuaternionWxyz(const CsvReader& reader, int first_col);

/// The 17 columns of a NavState row:
/// t,px,py,pz,qx,qy,qz,qw,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz.
std::vector<std::string> NavStateColumns();

/// Reads the NavStateColumns() at the start of the current row. Time must increase strictly
/// from row to row.
NavState ReadNavStateRow(CsvReader* reader);

/// The NavStateColumns() fields of one state, comma-separated (9-decimal seconds, %.17g).
std::string FormatNavStateRow(const NavState& state);
/// FormatNavStateRow appended to `out` (no line end).
void AppendNavStateRow(const NavState& state, std::string* out);

}  // namespace skerry
