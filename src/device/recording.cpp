#include "twinwatch/device/recording.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/core/numbers.hpp"

namespace twinwatch::device {

namespace {

// vector groups in file order: field flag (0 = always), prefix, member
struct Group {
  std::uint32_t flag;
  const char* prefix;
  VectorJ RobotSample::*member;
};
const Group kGroups[] = {
    {0, "actual_q_", &RobotSample::q},
    {kFieldActualQd, "actual_qd_", &RobotSample::qd},
    {kFieldTargetQ, "target_q_", &RobotSample::target_q},
    {kFieldTargetQd, "target_qd_", &RobotSample::target_qd},
    {kFieldTargetQdd, "target_qdd_", &RobotSample::target_qdd},
    {kFieldActualCurrent, "actual_current_", &RobotSample::current},
    {kFieldTargetCurrent, "target_current_", &RobotSample::target_current},
    {kFieldTargetMoment, "target_moment_", &RobotSample::target_moment},
    {kFieldTemperature, "joint_temperatures_", &RobotSample::temperature},
    {kFieldJointTorque, "actual_joint_torque_", &RobotSample::joint_torque},
    {kFieldCurrentAsTorque, "actual_current_as_torque_", &RobotSample::current_as_torque},
};
// a timestamp step longer than this many median periods marks a gap (lost samples)
constexpr double kGapFactor = 1.5;
// timestamps whose steps spread more than this fraction of the period are a jittery clock, whose gap
// factor is 1 + kJitterSigmas spreads (a controller's own clock: spread ~0)
constexpr double kJitterFraction = 0.05;
constexpr double kJitterSigmas = 5.0;

// a data row's cells, as views into `line` (no copies: a day's recording is tens of millions of
// rows), each trimmed of spaces, tabs and a line end's '\r'
void split_row(const std::string& line, std::vector<std::string_view>& out) {
  out.clear();
  const std::string_view all(line);
  const auto trimmed = [](std::string_view c) {
    const auto b = c.find_first_not_of(" \t\r");
    if (b == std::string_view::npos) return std::string_view();
    return c.substr(b, c.find_last_not_of(" \t\r") - b + 1);
  };
  size_t from = 0;
  for (size_t at = all.find(','); at != std::string_view::npos; at = all.find(',', from)) {
    out.push_back(trimmed(all.substr(from, at - from)));
    from = at + 1;
  }
  out.push_back(trimmed(all.substr(from)));
}

// a header's or a column map's cells, as strings: split_row's, with every '\r' dropped (one
// inside a name too, as these lines always were read)
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string_view> views;
  split_row(line, views);
  std::vector<std::string> out(views.begin(), views.end());
  for (std::string& cell : out) std::erase(cell, '\r');
  return out;
}

// the joint a column name carries after its group prefix ("actual_q_12" -> 12): -1 unless the
// rest is all digits; any index beyond the largest robot comes back as kMaxDof, however many digits
// it has (an int conversion of "actual_q_4000641156" would overflow)
int joint_index(const std::string& nm, std::size_t prefix_len) {
  if (nm.size() <= prefix_len || !std::all_of(nm.begin() + static_cast<long>(prefix_len), nm.end(), ::isdigit)) return -1;
  int j = 0;
  for (std::size_t i = prefix_len; i < nm.size() && j < kMaxDof; ++i) j = 10 * j + (nm[i] - '0');
  return std::min(j, kMaxDof);
}

// an RTDE name a recording column may carry
bool known_name(const std::string& nm) {
  if (nm == "timestamp" || nm == "actual_digital_output_bits" || nm == "robot_mode" || nm == "safety_mode" || nm == "stream_gap" ||
      nm == "payload" ||
      nm == "payload_cog_0" || nm == "payload_cog_1" || nm == "payload_cog_2")
    return true;
  for (const Group& g : kGroups) {
    const std::string p = g.prefix;
    if (nm.rfind(p, 0) == 0 && nm.size() > p.size() &&
        std::all_of(nm.begin() + static_cast<long>(p.size()), nm.end(), ::isdigit))
      return true;
  }
  return false;
}

std::string group_prefixes() {
  std::string s;
  for (const Group& g : kGroups) s += (s.empty() ? "" : ", ") + std::string(g.prefix);
  return s;
}

bool parse_double(std::string_view s, double& v) {
  if (s.empty()) return false;
  const char* b = s.data();
  const char* e = b + s.size();
  if (*b == '+') ++b;
  auto r = std::from_chars(b, e, v);
  return r.ec == std::errc() && r.ptr == e;
}

// the digits after a number's decimal point, up to its exponent (0 without a point)
int decimals_of(std::string_view s) {
  const size_t point = s.find('.');
  if (point == std::string_view::npos) return 0;
  const size_t exponent = s.find_first_of("eE", point);
  return static_cast<int>((exponent == std::string_view::npos ? s.size() : exponent) - point - 1);
}

}  // namespace

std::vector<std::string> recording_columns(int n, std::uint32_t fields) {
  std::vector<std::string> cols{"timestamp"};
  fields |= kFieldActualQd;
  for (const Group& g : kGroups)
    if (g.flag == 0 || (fields & g.flag))
      for (int j = 0; j < n; ++j) cols.push_back(fmt::format("{}{}", g.prefix, j));
  if (fields & kFieldDigitalOutputs) cols.push_back("actual_digital_output_bits");
  if (fields & kFieldRobotMode) cols.push_back("robot_mode");
  if (fields & kFieldSafetyMode) cols.push_back("safety_mode");
  if (fields & kFieldStreamGap) cols.push_back("stream_gap");
  if (fields & kFieldPayload)
    for (const char* c : {"payload", "payload_cog_0", "payload_cog_1", "payload_cog_2"}) cols.push_back(c);
  return cols;
}

ColumnMap ColumnMap::load(const std::string& path) {
  // (a directory opens as an empty stream: it would be an empty map, silently)
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw ParseError(path, 0, "", "cannot read the column map: it is a directory");
  std::ifstream f(path);
  if (!f) throw ParseError(path, 0, "", "cannot open the column map");
  ColumnMap m;
  m.path = path;
  std::string line;
  int ln = 0;
  while (std::getline(f, line)) {
    ++ln;
    // a byte-order mark (spreadsheet programs write one) as the recordings accept it
    if (ln == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const auto cells = split_csv(line);
    // the format's own names as a header line (the way docs/recordings.md writes the format): not
    // a mapping of a column called 'file_column'
    if (m.columns.empty() && cells.size() >= 2 && cells.size() <= 3 && cells[0] == "file_column" && cells[1] == "rtde_name" &&
        (cells.size() == 2 || cells[2] == "scale"))
      continue;
    if (cells.size() < 2 || cells.size() > 3)
      throw ParseError(path, ln, "", fmt::format("expected 'file_column,rtde_name[,scale]', got {} cells", cells.size()));
    Entry e{cells[1], 1.0};
    if (cells.size() == 3 && (!parse_double(cells[2], e.scale) || !std::isfinite(e.scale) || e.scale == 0.0))
      throw ParseError(path, ln, "scale", fmt::format("expected a finite non-zero number, got '{}'", cells[2]));
    if (cells[0].empty()) throw ParseError(path, ln, "file_column", "empty column name");
    if (!known_name(e.rtde_name))
      throw ParseError(path, ln, "rtde_name",
                       fmt::format("unknown name '{}', expected timestamp, actual_digital_output_bits, robot_mode, safety_mode, "
                                   "stream_gap, "
                                   "payload, payload_cog_0..2 or one of {}<joint> (joints from 0)", e.rtde_name, group_prefixes()));
    if (m.columns.count(cells[0]))
      throw ParseError(path, ln, "file_column", fmt::format("'{}' is already mapped on line {}", cells[0], m.lines[cells[0]]));
    m.columns[cells[0]] = e;
    m.lines[cells[0]] = ln;
  }
  // (an empty file mapped nothing: the recording was then read as if no map had been given)
  if (m.columns.empty())
    throw ParseError(path, ln, "", "the column map maps no column: expected lines 'file_column,rtde_name[,scale]' (docs/recordings.md)");
  return m;
}

RecordingReader::RecordingReader(const std::string& path_in, const ColumnMap* map) : path(path_in) {
  refuse_directory_input(path);
  f.open(path);
  if (!f) throw ParseError(path, 0, "", "cannot open the recording (does it exist and is it readable?)");
  std::string line;
  if (!std::getline(f, line)) throw ParseError(path, 1, "", "empty file, expected a header of RTDE names");
  // a UTF-8 byte-order mark (spreadsheet programs write one) is not part of the first name
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
  header = split_csv(line);
  scale.assign(header.size(), 1.0);
  // a header in one cell that another separator splits, or quoted names: said wherever a name is
  // missed (a column map's first missing column too: audit of session 56)
  std::string separator_hint;
  if (header.size() == 1 && (line.find(';') != std::string::npos || line.find('\t') != std::string::npos))
    separator_hint = fmt::format(": the header is one cell, its names separated by {}; twinwatch reads comma-separated files",
                                 line.find(';') != std::string::npos ? "';'" : "tabs");
  else if (line.find('"') != std::string::npos)
    separator_hint = ": the header's names are quoted; twinwatch reads them unquoted";
  std::vector<std::string> names = header;
  if (map) {
    // every mapped column must exist: a typo in the map would otherwise drop a signal silently
    for (const auto& [col, entry] : map->columns)
      if (std::find(header.begin(), header.end(), col) == header.end()) {
        const auto at = map->lines.find(col);
        throw ParseError(path, 1, col,
                         fmt::format("column map{} maps column '{}' to {}, but the header has no such column{}",
                                     map->path.empty() ? "" : fmt::format(" ({} line {})", map->path, at == map->lines.end() ? 0 : at->second),
                                     col, entry.rtde_name, separator_hint));
      }
    for (size_t c = 0; c < header.size(); ++c) {
      auto it = map->columns.find(header[c]);
      if (it != map->columns.end()) {
        names[c] = it->second.rtde_name;
        scale[c] = it->second.scale;
      }
    }
  }
  // the names as the file or its map gives them, for messages (before a torque twin's renaming)
  const std::vector<std::string> given_names = names;
  if (map && map->joint_torque_as_current) {
    // the twin's measured channel is the joint torque sensors': their columns fill the current's
    // place, and the motor currents (a Kinova logs both) are not read; nor is the controller's target
    // acceleration: the sensors read the link's own (read_as_joint_torque does the same in memory)
    bool any = false;
    for (std::string& nm : names) {
      if (nm.rfind("actual_current_", 0) == 0 && nm.rfind("actual_current_as_torque_", 0) != 0) nm.clear();
      else if (nm.rfind("target_qdd_", 0) == 0) nm.clear();
      else if (nm.rfind("actual_joint_torque_", 0) == 0) {
        nm = "actual_current_" + nm.substr(std::strlen("actual_joint_torque_"));
        any = true;
      }
    }
    if (!any)
      throw ParseError(path, 1, "actual_joint_torque_0",
                       "missing required column: the twin compares joint torque sensors (its signal is joint_torque), and the header "
                       "has no actual_joint_torque_* (map the log's torque columns onto them with --column-map, docs/recordings.md)");
  }
  // locate columns: each known name -> (group, joint)
  for (size_t c = 0; c < names.size(); ++c) {
    if (names[c].rfind("actual_q_", 0) != 0) continue;
    const int j = joint_index(names[c], 9);
    if (j >= kMaxDof)
      throw ParseError(path, 1, header[c],
                       fmt::format("expected a joint 0 to {} (at most {} joints supported), got '{}'", kMaxDof - 1, kMaxDof, names[c]));
    n = std::max(n, j + 1);
  }
  if (n == 0) {
    throw ParseError(path, 1, "actual_q_0", "missing required column (no actual_q_* in the header)" + separator_hint);
  }
  target.assign(names.size(), Target{-1, -1});
  std::vector<std::vector<bool>> seen(std::size(kGroups), std::vector<bool>(static_cast<size_t>(n), false));
  for (size_t c = 0; c < names.size(); ++c) {
    const std::string& nm = names[c];
    if (nm == "timestamp") ts_col = static_cast<int>(c);
    else if (nm == "actual_digital_output_bits") do_col = static_cast<int>(c);
    else if (nm == "robot_mode") mode_col = static_cast<int>(c);
    else if (nm == "safety_mode") safety_col = static_cast<int>(c);
    else if (nm == "stream_gap") gap_col = static_cast<int>(c);
    else if (nm == "payload") payload_col = static_cast<int>(c);
    else if (nm.size() == 13 && nm.rfind("payload_cog_", 0) == 0 && nm[12] >= '0' && nm[12] <= '2') cog_col[nm[12] - '0'] = static_cast<int>(c);
    else {
      // longest matching prefix first (actual_qd_ before actual_q_)
      int best = -1;
      size_t best_len = 0;
      for (size_t g = 0; g < std::size(kGroups); ++g) {
        const std::string p = kGroups[g].prefix;
        if (nm.rfind(p, 0) == 0 && p.size() > best_len && joint_index(nm, p.size()) >= 0) {
          best = static_cast<int>(g);
          best_len = p.size();
        }
      }
      if (best >= 0) {
        const int j = joint_index(nm, best_len);
        // a joint the positions do not have: its data would be dropped without a word
        if (j >= n)
          throw ParseError(path, 1, header[c],
                           fmt::format("column {} is '{}', joint index {}, but the recording's positions are actual_q_0..actual_q_{} "
                                       "({} joints): expected an index below {}",
                                       c + 1, nm, j, n - 1, n, n));
        target[c] = {best, j};
        seen[static_cast<size_t>(best)][static_cast<size_t>(j)] = true;
      }
    }
  }
  // the same signal twice: one copy would win silently and the other's data would be lost
  for (size_t c = 0; c < names.size(); ++c) {
    if (names[c].empty() || !known_name(names[c])) continue;
    for (size_t d = c + 1; d < names.size(); ++d)
      if (names[d] == names[c]) {
        // (the map's lines, when the map made them the same)
        std::string lines;
        if (map) {
          const auto a = map->lines.find(header[c]), b = map->lines.find(header[d]);
          if (a != map->lines.end() && b != map->lines.end())
            lines = fmt::format("; the column map{} maps both, lines {} and {}", map->path.empty() ? "" : " " + map->path, a->second, b->second);
        }
        throw ParseError(path, 1, header[d],
                         fmt::format("column {} is '{}' again (column {} is '{}'{}): expected each signal once",
                                     d + 1, given_names[d], c + 1, header[c], lines));
      }
  }
  if (ts_col < 0) throw ParseError(path, 1, "timestamp", "missing required column");
  for (int j = 0; j < n; ++j)
    if (!seen[0][static_cast<size_t>(j)]) throw ParseError(path, 1, fmt::format("actual_q_{}", j), "missing required column");
  // a group is present only when all its joints are
  for (size_t g = 1; g < std::size(kGroups); ++g) {
    const bool all = std::all_of(seen[g].begin(), seen[g].end(), [](bool b) { return b; });
    const bool any = std::any_of(seen[g].begin(), seen[g].end(), [](bool b) { return b; });
    if (any && !all) {
      // (a joint-torque twin's channel is read from the sensors' columns: they are the ones missing)
      const std::string prefix = map && map->joint_torque_as_current && kGroups[g].flag == kFieldActualCurrent ? "actual_joint_torque_"
                                                                                                                : kGroups[g].prefix;
      throw ParseError(path, 1, prefix + "*", fmt::format("some joints' columns are missing (expected {}0..{}{})", prefix, prefix, n - 1));
    }
    if (all) present_ |= kGroups[g].flag;
  }
  if (do_col >= 0) present_ |= kFieldDigitalOutputs;
  if (mode_col >= 0) present_ |= kFieldRobotMode;
  if (safety_col >= 0) present_ |= kFieldSafetyMode;
  if (gap_col >= 0) present_ |= kFieldStreamGap;
  // the declared payload: its mass and centre of mass together (a mass without its centre, or the
  // reverse, cannot be taken by the twin and would be dropped without a word)
  {
    const int cogs = (cog_col[0] >= 0) + (cog_col[1] >= 0) + (cog_col[2] >= 0);
    if ((payload_col >= 0 || cogs > 0) && !(payload_col >= 0 && cogs == 3))
      throw ParseError(path, 1, payload_col >= 0 ? "payload_cog_*" : "payload",
                       fmt::format("the declared payload needs its mass and centre of mass together: expected the columns payload, "
                                   "payload_cog_0, payload_cog_1 and payload_cog_2, the header has {}{} of the three payload_cog_*",
                                   payload_col >= 0 ? "payload and " : "no payload and ", cogs));
    if (payload_col >= 0) present_ |= kFieldPayload;
  }
}

int RecordingReader::n_dof() const { return n; }

bool RecordingReader::reads(size_t column) const {
  const int c = static_cast<int>(column);
  return c == ts_col || c == do_col || c == mode_col || c == safety_col || c == gap_col || c == payload_col || c == cog_col[0] ||
         c == cog_col[1] || c == cog_col[2] || target[column].group >= 0;
}

std::uint32_t RecordingReader::present() const { return present_; }

bool RecordingReader::next(RobotSample& s) {
  std::string& line = line_;
  std::vector<std::string_view>& cells = cells_;
  while (std::getline(f, line)) {
    ++ln;
    if (line.empty() || line == "\r") continue;
    split_row(line, cells);
    // the last row of a recording cut off mid-write (a killed recorder, a power loss): fewer cells
    // and no line end. It is dropped, and said; anywhere else a short row is an error
    if (cells.size() < header.size() && f.eof()) {
      if (say_cut_)
        log::warn(fmt::format("{}:{}: the last row is cut off ({} of {} cells, no line end): dropped, as a recording interrupted "
                            "mid-write leaves it",
                            path, ln, cells.size(), header.size()));
      return false;
    }
    // ... or with all its cells and the last one cut mid-number: empty, ending in '.', 'e' or a
    // sign (no writer ends a number so), or with fewer decimals than that column had in every row
    // before (a writer of fixed decimals: the same count in 10 rows or more). A shortest-form writer's cell
    // ("%g", to_chars) cut after a digit looks like a shorter number and cannot be told: it is
    // read as it is
    if (cells.size() == header.size() && f.eof() && reads(cells.size() - 1)) {
      const std::string_view last = cells.back();
      const int decimals = decimals_of(last);
      const bool mid_number = last.empty() || std::string_view(".eE+-").find(last.back()) != std::string_view::npos;
      const bool short_decimals = rows >= 10 && fixed_decimals_ && last_cell_decimals_ > 0 && decimals < last_cell_decimals_;
      if (mid_number || short_decimals) {
        if (say_cut_)
          log::warn(fmt::format("{}:{}: the last row is cut off (its last cell '{}'{}, no line end): dropped, as a recording "
                                "interrupted mid-write leaves it",
                                path, ln, last,
                                mid_number ? " ends mid-number"
                                           : fmt::format(" has {} decimal(s), every row before had {}", decimals, last_cell_decimals_)));
        return false;
      }
    }
    if (cells.size() != header.size())
      throw ParseError(path, ln, "", fmt::format("expected {} cells (as in the header), got {}", header.size(), cells.size()));
    hash_ = (hash_ ^ std::hash<std::string_view>{}(line)) * 1099511628211ull;  // (FNV-style mixing of each row's hash)
    s = RobotSample::empty(n);
    s.present = present_;
    for (size_t c = 0; c < cells.size(); ++c) {
      const int ci = static_cast<int>(c);
      const bool cog = ci == cog_col[0] || ci == cog_col[1] || ci == cog_col[2];
      if (!reads(c)) continue;
      double v;
      if (!parse_double(cells[c], v))
        throw ParseError(path, ln, header[c], fmt::format("expected a number, got '{}'", cells[c]));
      // nan or inf in one cell would run through every filter and observer state after it and
      // blind the monitor for the rest of the recording: refuse it here, where file and line are known
      v *= scale[c];
      if (!std::isfinite(v))
        throw ParseError(path, ln, header[c],
                         fmt::format("expected a finite number, got '{}'{}", cells[c], scale[c] == 1.0 ? "" : " (after the column map's scale)"));
      if (static_cast<int>(c) == ts_col) s.timestamp = v;
      else if (static_cast<int>(c) == do_col) {
        // a bit mask: a whole number 0 to 2^64-1, exact when written as an integer (as the writer
        // does); a cast of anything else to uint64 would be undefined
        std::uint64_t bits = 0;
        const char* e = cells[c].data() + cells[c].size();
        const auto r = std::from_chars(cells[c].data(), e, bits);
        if (scale[c] == 1.0 && r.ec == std::errc() && r.ptr == e) s.digital_outputs = bits;
        else if (v >= 0.0 && v < 0x1p64 && v == std::floor(v)) s.digital_outputs = static_cast<std::uint64_t>(v);
        else throw ParseError(path, ln, header[c], fmt::format("expected a whole number 0 to 2^64-1 (a bit mask), got '{}'", cells[c]));
      } else if (static_cast<int>(c) == mode_col) {
        const std::optional<int> mode = whole_int(v);
        if (!mode) throw ParseError(path, ln, header[c], fmt::format("expected a whole number (an RTDE robot mode), got '{}'", cells[c]));
        s.robot_mode = *mode;
      } else if (ci == safety_col) {
        const std::optional<int> mode = whole_int(v);
        if (!mode) throw ParseError(path, ln, header[c], fmt::format("expected a whole number (an RTDE safety mode), got '{}'", cells[c]));
        s.safety_mode = *mode;
      }
      else if (static_cast<int>(c) == gap_col) {
        if (v != 0.0 && v != 1.0) throw ParseError(path, ln, header[c], fmt::format("expected 0 or 1, got '{}'", cells[c]));
        s.gap_before = v != 0.0;
      } else if (ci == payload_col) {
        if (v < 0.0) throw ParseError(path, ln, header[c], fmt::format("expected a payload mass >= 0 kg, got '{}'", cells[c]));
        s.payload = v;
      } else if (cog) {
        s.payload_cog[ci == cog_col[0] ? 0 : (ci == cog_col[1] ? 1 : 2)] = v;
      } else (s.*kGroups[static_cast<size_t>(target[c].group)].member)[target[c].joint] = v;
    }
    // (as written, and in seconds after a map's scale: '698' was said as 0.6980000000000001)
    if (rows > 0 && !(s.timestamp > last_timestamp)) {
      const size_t tc = static_cast<size_t>(ts_col);
      throw ParseError(path, ln, header[tc],
                       scale[tc] == 1.0 ? fmt::format("timestamp {:.10g} does not increase (previous {:.10g})", s.timestamp, last_timestamp)
                                        : fmt::format("timestamp '{}' ({:.10g} s after the column map's scale) does not increase (previous "
                                                      "{:.10g} s)",
                                                      cells[tc], s.timestamp, last_timestamp));
    }
    last_timestamp = s.timestamp;
    // (a writer of fixed decimals: the same count in every row; "%g" drops trailing zeros, and its
    // whole -0.19871 for -0.198710 was dropped as cut: review of session 56)
    const int decimals = decimals_of(cells.back());
    fixed_decimals_ = last_cell_decimals_ < 0 || (fixed_decimals_ && decimals == last_cell_decimals_);
    last_cell_decimals_ = decimals;
    ++rows;
    return true;
  }
  return false;
}

RecordingScan scan_rows(RecordingReader& reader, const std::function<void(const RobotSample&)>& each) {
  RecordingScan scan;
  std::vector<double> dts;
  RobotSample s;
  double previous = 0.0;
  while (reader.next(s)) {
    if (scan.rows++ > 0) dts.push_back(s.timestamp - previous);
    previous = s.timestamp;
    each(s);
  }
  if (scan.rows == 0) throw ParseError(reader.file(), 2, "", "no data rows after the header");
  scan.timing = recording_timing(reader.file(), std::move(dts));
  scan.n_dof = reader.n_dof();
  scan.present = reader.present();
  scan.rows_hash = reader.rows_hash();
  return scan;
}

void require_rereadable(const std::string& path, const std::string& user) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) && !std::filesystem::is_directory(st))
    throw InvalidArgument(fmt::format("{}: {} reads a recording twice or more (a check of every row, then the work) and never holds it; "
                                      "this is not a file that can be read again (a pipe, a process substitution, /dev/stdin?): save it "
                                      "to a file first",
                                      path, user));
}

namespace {
// A reader opened again for the second pass over rows a scan checked (replay_rows, FileSamples): its
// header must be the scan's; each row gets gap_before from the scan's timing, as read_recording
// marks it; check_hash() once all the scan's rows are read.
void check_header(RecordingReader& again, const RecordingScan& scan) {
  again.quiet();  // (a cut-off last row was said by the scan)
  if (again.n_dof() != scan.n_dof || again.present() != scan.present)
    throw std::runtime_error(fmt::format("{}: its header changed while it was read (another program writing it?): read a copy", again.file()));
}
void mark_gap(RobotSample& s, long k, double previous, const RecordingScan& scan) {
  if (k > 0 && scan.timing.is_gap(s.timestamp - previous)) s.gap_before = true;
}
void check_hash(const RecordingReader& again, const RecordingScan& scan) {
  if (again.rows_hash() != scan.rows_hash)
    throw std::runtime_error(fmt::format("{}: its rows changed while it was read (replaced or rewritten by another program?): read a copy",
                                         again.file()));
}
}  // namespace

long replay_rows(RecordingReader& again, const RecordingScan& scan, const std::function<void(RobotSample&)>& each) {
  check_header(again, scan);
  RobotSample s;
  double previous = 0.0;
  long k = 0;
  for (; k < scan.rows && again.next(s); ++k) {
    mark_gap(s, k, previous, scan);
    previous = s.timestamp;
    each(s);
  }
  if (k == scan.rows) check_hash(again, scan);
  return k;
}

Recording read_recording(const std::string& path, const ColumnMap* map) {
  RecordingReader reader(path, map);
  Recording rec;
  rec.path = path;
  rec.n_dof = reader.n_dof();
  rec.present = reader.present();
  const RecordingTiming timing = scan_rows(reader, [&](const RobotSample& s) { rec.samples.push_back(s); }).timing;
  rec.median_period = timing.median_period;
  rec.period_jitter = timing.period_jitter;
  rec.gap_factor = timing.gap_factor;
  // gaps: steps longer than the gap factor times the median period
  for (size_t k = 1; k < rec.samples.size(); ++k)
    if (timing.is_gap(rec.samples[k].timestamp - rec.samples[k - 1].timestamp)) rec.samples[k].gap_before = true;
  // a gap is a marker in the file's stream_gap column or a timestamp jump, or both
  for (const RobotSample& x : rec.samples) rec.gaps += x.gap_before ? 1 : 0;
  return rec;
}

std::uint32_t read_as_joint_torque(std::uint32_t present) {
  const bool sensed = (present & kFieldJointTorque) != 0;
  present &= ~(kFieldJointTorque | kFieldTargetQdd | kFieldActualCurrent);
  return sensed ? present | kFieldActualCurrent : present;
}

void read_as_joint_torque(RobotSample& s) {
  s.current = s.joint_torque;
  s.present = read_as_joint_torque(s.present);
}

RecordingTiming recording_timing(const std::string& path, std::vector<double> dts) {
  RecordingTiming t;
  t.gap_factor = kGapFactor;
  if (dts.empty()) return t;
  // (the steps are this function's own copy: ordered in place)
  std::nth_element(dts.begin(), dts.begin() + static_cast<long>(dts.size() / 2), dts.end());
  t.median_period = dts[dts.size() / 2];
  // a logger's own clock (a PC stamping what it receives) jitters: its steps spread around the
  // period, and a lost sample (a step of two periods) cannot be told from a late stamp. The
  // spread (1.4826 x the median absolute deviation of the steps) then raises the gap factor to
  // kJitterSigmas spreads above the period, and the file says so once
  for (double& d : dts) d = std::abs(d - t.median_period);  // (the deviations, in the steps' place)
  std::nth_element(dts.begin(), dts.begin() + static_cast<long>(dts.size() / 2), dts.end());
  t.period_jitter = 1.4826 * dts[dts.size() / 2];
  if (t.median_period > 0.0 && t.period_jitter > kJitterFraction * t.median_period) {
    t.gap_factor = jitter_gap_factor(t.period_jitter, t.median_period, kGapFactor);
    log::warn(fmt::format("{}: the timestamps jitter (spread {:.2f} ms around the {:.2f} ms period; a logger's own clock?): a step "
                          "counts as lost samples only above {:.1f} ms, shorter losses cannot be told from the jitter",
                          path, 1000.0 * t.period_jitter, 1000.0 * t.median_period, 1000.0 * t.gap_factor * t.median_period));
  }
  return t;
}

double jitter_gap_factor(double spread, double period, double floor) {
  return std::max(floor, 1.0 + kJitterSigmas * spread / period);
}

void DrivenStretches::see(const RobotSample& s) {
  if (k_ == 0) first_sample_ = s.timestamp;
  last_sample_ = s.timestamp;
  if (s.driven()) {
    if (!in_) {
      in_ = true;
      begin_ = k_;
      began_ = s.timestamp;
    }
    last_ = s.timestamp;
  } else {
    close();
    ++not_driven_;
  }
  ++k_;
}

void DrivenStretches::close() {
  if (!in_) return;
  in_ = false;
  if (last_ - began_ >= min_seconds_) {
    stretches_.push_back({begin_, k_, began_, last_});
  } else {
    short_samples_ += static_cast<long>(k_ - begin_);
    ++short_stretches_;
  }
}

void DrivenStretches::finish() { close(); }

std::vector<DrivenStretches::Stretch> DrivenStretches::used() const {
  if (!whole()) return stretches_;
  if (k_ == 0) return {};
  return {{0, k_, first_sample_, last_sample_}};
}

std::string DrivenStretches::note(const std::string& path, double period) const {
  if (whole()) return {};
  period = period > 0.0 ? period : 0.0;
  return fmt::format("{}: {} sample(s){} in which the controller did not drive the arm (robot_mode not RUNNING or safety_mode "
                     "not NORMAL/REDUCED: a stop, power off, brakes on) are left out{}; {} driven stretch(es) are used",
                     path, not_driven_, period > 0.0 ? fmt::format(" ({:.1f} s)", static_cast<double>(not_driven_) * period) : "",
                     short_stretches_ > 0 ? fmt::format(", and {} driven stretch(es) shorter than {:g} s ({} samples)", short_stretches_,
                                                        min_seconds_, short_samples_)
                                          : "",
                     stretches_.size());
}

std::vector<Recording> driven_segments(const Recording& rec, double min_seconds, std::string* left_out) {
  if (left_out) left_out->clear();
  DrivenStretches driven(min_seconds);
  for (const RobotSample& s : rec.samples) driven.see(s);
  driven.finish();
  if (driven.whole()) return {rec};
  std::vector<Recording> out;
  for (const auto& [k, e, first, last] : driven.stretches()) {
    Recording seg;
    seg.path = rec.path, seg.n_dof = rec.n_dof, seg.present = rec.present;
    seg.median_period = rec.median_period, seg.period_jitter = rec.period_jitter, seg.gap_factor = rec.gap_factor;
    seg.samples.assign(rec.samples.begin() + static_cast<long>(k), rec.samples.begin() + static_cast<long>(e));
    seg.samples.front().gap_before = false;  // the segment starts here
    seg.gaps = 0;
    for (const RobotSample& s : seg.samples) seg.gaps += s.gap_before ? 1 : 0;
    out.push_back(std::move(seg));
  }
  if (left_out) *left_out = driven.note(rec.path, rec.median_period);
  return out;
}

HeldSamples::HeldSamples(const Recording& rec) : rec_(&rec) {
  path_ = rec.path;
  n_dof_ = rec.n_dof;
  present_ = rec.present;
  median_period_ = rec.median_period;
  size_ = rec.samples.size();
  seconds_ = size_ > 1 ? rec.samples.back().timestamp - rec.samples.front().timestamp : 0.0;
}

void HeldSamples::replay(const std::function<void(size_t k, const RobotSample& s)>& each) const {
  for (size_t k = 0; k < rec_->samples.size(); ++k) each(k, rec_->samples[k]);
}

struct FileSamples::Reading {
  std::string path;
  const ColumnMap* map;
  RecordingScan scan;
  std::unique_ptr<RecordingReader> reader;  // null: to be opened
  long row = 0;                             // the next row it reads
  double previous = 0.0;                    // the timestamp of the row before it
};

std::vector<std::unique_ptr<FileSamples>> FileSamples::of(const std::string& path, const ColumnMap* map, const RecordingScan& scan,
                                                          const DrivenStretches& driven) {
  auto reading = std::make_shared<Reading>(Reading{path, map, scan, nullptr, 0, 0.0});
  const std::vector<DrivenStretches::Stretch> stretches = driven.used();
  std::vector<std::unique_ptr<FileSamples>> out;
  for (size_t i = 0; i < stretches.size(); ++i)
    out.push_back(std::unique_ptr<FileSamples>(new FileSamples(reading, stretches[i], driven.whole(), i + 1 == stretches.size())));
  return out;
}

FileSamples::FileSamples(std::shared_ptr<Reading> reading, DrivenStretches::Stretch stretch, bool whole, bool last)
    : reading_(std::move(reading)), stretch_(stretch), whole_(whole), last_(last) {
  path_ = reading_->path;
  n_dof_ = reading_->scan.n_dof;
  present_ = reading_->scan.present;
  median_period_ = reading_->scan.timing.median_period;
  size_ = stretch.end - stretch.begin;
  seconds_ = size_ > 1 ? stretch.last - stretch.first : 0.0;
}

void FileSamples::replay(const std::function<void(size_t k, const RobotSample& s)>& each) const {
  Reading& r = *reading_;
  const long begin = static_cast<long>(stretch_.begin), end = static_cast<long>(stretch_.end);
  // (replay_rows, a stretch at a time)
  if (!r.reader || r.row > begin) {
    auto again = std::make_unique<RecordingReader>(r.path, r.map);
    check_header(*again, r.scan);
    r.reader = std::move(again);
    r.row = 0;
  }
  try {
    RobotSample s;
    const long stop = last_ ? r.scan.rows : end;  // (the last stretch reads on to the end, for the hash)
    for (; r.row < stop; ++r.row) {
      if (!r.reader->next(s))
        throw std::runtime_error(fmt::format("{}: {} of the {} rows checked were there to learn from (the file was cut or replaced while "
                                             "it was read): read a copy",
                                             r.path, r.row, r.scan.rows));
      mark_gap(s, r.row, r.previous, r.scan);
      r.previous = s.timestamp;
      if (r.row < begin || r.row >= end) continue;
      if (r.row == begin && !whole_) s.gap_before = false;  // (a driven stretch starts here: driven_segments)
      each(static_cast<size_t>(r.row - begin), s);
    }
    if (last_) check_hash(*r.reader, r.scan);
  } catch (...) {
    r.reader.reset();  // (read again from the start next time)
    throw;
  }
}

namespace {
void require_fields(const std::string& path, int n_dof, std::uint32_t present, std::uint32_t fields, const std::string& user) {
  for (const Group& g : kGroups)
    if (g.flag != 0 && (fields & g.flag) && !(present & g.flag))
      throw ParseError(path, 1, fmt::format("{}0", g.prefix),
                       fmt::format("missing required column: {} needs {}0..{}{}, the header has none of them", user, g.prefix,
                                   g.prefix, n_dof - 1));
}
}  // namespace

void require_fields(const Recording& rec, std::uint32_t fields, const std::string& user) {
  require_fields(rec.path, rec.n_dof, rec.present, fields, user);
}

void require_fields(const RecordingReader& reader, std::uint32_t fields, const std::string& user) {
  require_fields(reader.file(), reader.n_dof(), reader.present(), fields, user);
}

RecordingWriter::RecordingWriter(const std::string& path, int n_dof, std::uint32_t fields)
    : path_(path), n_(n_dof), fields_(fields | kFieldActualQd) {
  if (n_dof < 1 || n_dof > kMaxDof)
    throw InvalidArgument(fmt::format("recording n_dof is {}, expected 1 to {}", n_dof, kMaxDof));
  f_ = std::fopen(path.c_str(), "w");
  if (!f_) throw PathError(path + ": cannot open for writing: " + std::strerror(errno));
  std::string h;
  for (const auto& c : recording_columns(n_, fields_)) h += (h.empty() ? "" : ",") + c;
  h += '\n';
  std::fputs(h.c_str(), f_);
}

RecordingWriter::~RecordingWriter() {
  if (f_) std::fclose(f_);
}

void RecordingWriter::write(const RobotSample& s) {
  line_.clear();
  char buf[40];
  auto put = [&](double v) {
    auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest round-trip representation
    line_.append(buf, r.ptr);
  };
  put(s.timestamp);
  for (const Group& g : kGroups) {
    if (g.flag != 0 && !(fields_ & g.flag)) continue;
    const VectorJ& v = s.*g.member;
    for (int j = 0; j < n_; ++j) {
      line_ += ',';
      put(j < v.size() ? v[j] : std::numeric_limits<double>::quiet_NaN());
    }
  }
  if (fields_ & kFieldDigitalOutputs) line_ += fmt::format(",{}", s.digital_outputs);
  if (fields_ & kFieldRobotMode) line_ += fmt::format(",{}", s.robot_mode);
  if (fields_ & kFieldSafetyMode) line_ += fmt::format(",{}", s.safety_mode);
  if (fields_ & kFieldStreamGap) line_ += s.gap_before ? ",1" : ",0";
  if (fields_ & kFieldPayload) {
    line_ += ',';
    put(s.payload);
    for (double c : s.payload_cog) {
      line_ += ',';
      put(c);
    }
  }
  line_ += '\n';
  // a failed write stops at once (a disk that fills during an hour of recording is said then, not
  // at the end with the rest of the hour lost); the rows before it are in the file
  if (std::fwrite(line_.data(), 1, line_.size(), f_) != line_.size())
    throw std::runtime_error(fmt::format("{}: write error after {} rows (disk full?)", path_, rows_));
  ++rows_;
}

void RecordingWriter::close() {
  if (!f_) return;
  const bool bad = std::ferror(f_) != 0;
  const int rc = std::fclose(f_);
  f_ = nullptr;
  if (bad || rc != 0) throw std::runtime_error(path_ + ": write error (disk full?)");
}

}  // namespace twinwatch::device

namespace twinwatch::device {

std::string split_recording_name(const std::string& path, long k) {
  const std::filesystem::path p(path);
  return (p.parent_path() / fmt::format("{}.{:03d}{}", p.stem().string(), k, p.extension().string())).string();
}

std::string SplitRecordingWriter::first_file(const std::string& path, double every_s) {
  return every_s > 0.0 ? split_recording_name(path, 0) : path;
}

SplitRecordingWriter::SplitRecordingWriter(const std::string& path, int n_dof, std::uint32_t fields, double every_s)
    : path_(path), n_(n_dof), fields_(fields), every_(every_s), file_start_(std::numeric_limits<double>::quiet_NaN()) {
  if (!valid_interval(every_s))
    throw InvalidArgument(fmt::format("a recording's split interval must be 0 (one file) or a finite time >= 1 s of controller time, got {}",
                                      every_s));
  const std::string first = first_file(path_, every_);
  writer_ = std::make_unique<RecordingWriter>(first, n_, fields_);
  files_.push_back(first);
  // parts of an earlier, longer run are overwritten only as far as this run reaches
  if (every_ > 0.0 && std::filesystem::exists(split_recording_name(path_, 1)))
    log::warn(fmt::format("{} exists (an earlier run?): this run's parts replace it and the ones after it only as far as it goes; "
                          "what is left belongs to the earlier run",
                          split_recording_name(path_, 1)));
}

void SplitRecordingWriter::write(const RobotSample& s) {
  if (!writer_) throw std::logic_error(fmt::format("{}: written after it was closed", files_.back()));
  if (every_ > 0.0) {
    if (std::isnan(file_start_)) file_start_ = s.timestamp;
    // (a controller clock that went back, a restart during a reconnection, starts a file too: a
    // file's timestamps only increase)
    if (s.timestamp - file_start_ >= every_ || s.timestamp <= last_t_) {
      writer_->close();
      const std::string next = split_recording_name(path_, static_cast<long>(files_.size()));
      writer_ = std::make_unique<RecordingWriter>(next, n_, fields_);
      files_.push_back(next);
      file_start_ = s.timestamp;
    }
    last_t_ = s.timestamp;
  }
  writer_->write(s);
  ++rows_;
}

void SplitRecordingWriter::close() {
  if (!writer_) return;
  std::unique_ptr<RecordingWriter> w = std::move(writer_);
  w->close();
}

}  // namespace twinwatch::device
