#include "twinwatch/device/rtde_protocol.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <unordered_map>

namespace twinwatch::device::rtde {

namespace {

// ---- big-endian primitives (fact sheet §1). memcpy + bswap compiles to a load and a bswap.
inline std::uint16_t be16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }
inline std::uint32_t be32(const std::uint8_t* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  return __builtin_bswap32(v);
}
inline std::uint64_t be64(const std::uint8_t* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return __builtin_bswap64(v);
}
inline double bed(const std::uint8_t* p) {
  const std::uint64_t u = be64(p);
  double d;
  std::memcpy(&d, &u, 8);
  return d;
}
inline void put8(Bytes& o, std::uint8_t v) { o.push_back(v); }
inline void put16(Bytes& o, std::uint16_t v) {
  o.push_back(static_cast<std::uint8_t>(v >> 8));
  o.push_back(static_cast<std::uint8_t>(v));
}
inline void put32(std::uint8_t* p, std::uint32_t v) {
  v = __builtin_bswap32(v);
  std::memcpy(p, &v, 4);
}
inline void put64(std::uint8_t* p, std::uint64_t v) {
  v = __builtin_bswap64(v);
  std::memcpy(p, &v, 8);
}
inline void putd(std::uint8_t* p, double d) {
  std::uint64_t u;
  std::memcpy(&u, &d, 8);
  put64(p, u);
}

// Starts a package: reserves the header, returns the offset of the package start.
std::size_t begin(Bytes& o, PackageType t) {
  const std::size_t at = o.size();
  put16(o, 0);
  put8(o, static_cast<std::uint8_t>(t));
  return at;
}
// Patches the size field (whole package, header included — fact sheet §2).
void finish(Bytes& o, std::size_t at) {
  const std::size_t size = o.size() - at;
  if (size > 0xFFFF) throw ProtocolError(fmt::format("package of {} bytes exceeds the 16-bit size field", size));
  o[at] = static_cast<std::uint8_t>(size >> 8);
  o[at + 1] = static_cast<std::uint8_t>(size);
}
void put_text(Bytes& o, std::string_view s) { o.insert(o.end(), s.begin(), s.end()); }

void expect_size(const Package& p, std::size_t n, const char* what) {
  if (p.payload.size() != n)
    throw ProtocolError(fmt::format("{}: expected a {}-byte payload ({}), got {} bytes", package_name(p.type), n, what,
                                    p.payload.size()));
}

std::string printable(std::span<const std::uint8_t> s) {
  std::string out;
  for (std::uint8_t c : s) {
    if (c < 0x20 || c > 0x7e) throw ProtocolError(fmt::format("non-ASCII byte 0x{:02x} in a name or type list", c));
    out += static_cast<char>(c);
  }
  return out;
}

// Fields in table order, each with its first scalar's slot in a frame.
struct FieldTable {
  std::vector<FieldInfo> fields;
  int slot = 0;
  void add(std::string name, DataType t) {
    fields.push_back({std::move(name), t, slot});
    slot += value_count(t);
  }
};

std::vector<FieldInfo> make_output_fields() {
  FieldTable table;
  auto add = [&](std::string name, DataType t) { table.add(std::move(name), t); };
  using T = DataType;
  add("timestamp", T::Double);
  for (const char* n : {"target_q", "target_qd", "target_qdd", "target_current", "target_moment", "actual_q", "actual_qd",
                        "actual_current", "actual_current_window", "actual_current_as_torque", "joint_control_output",
                        "actual_TCP_pose", "actual_TCP_speed", "actual_TCP_force", "target_TCP_pose", "target_TCP_speed",
                        "ft_raw_wrench", "wrench_calc_from_currents", "joint_temperatures", "actual_joint_voltage",
                        "payload_inertia"})
    add(n, T::Vector6d);
  add("joint_mode", T::Vector6Int32);
  for (const char* n : {"robot_mode", "safety_mode", "safety_status"}) add(n, T::Int32);
  for (const char* n : {"runtime_state", "robot_status_bits", "safety_status_bits", "output_bit_registers0_to_31",
                        "output_bit_registers32_to_63"})
    add(n, T::Uint32);
  for (const char* n : {"speed_scaling", "target_speed_fraction", "actual_momentum", "actual_main_voltage",
                        "actual_robot_voltage", "actual_robot_current", "actual_execution_time",
                        "joint_position_deviation_ratio", "collision_detection_ratio", "payload", "standard_analog_input0",
                        "standard_analog_input1", "standard_analog_output0", "standard_analog_output1"})
    add(n, T::Double);
  for (const char* n : {"actual_tool_accelerometer", "payload_cog", "elbow_position", "elbow_velocity"}) add(n, T::Vector3d);
  for (const char* n : {"actual_digital_input_bits", "actual_digital_output_bits"}) add(n, T::Uint64);
  for (int i = 0; i < 48; ++i) add(fmt::format("output_int_register_{}", i), T::Int32);
  for (int i = 0; i < 48; ++i) add(fmt::format("output_double_register_{}", i), T::Double);
  for (int i = 64; i < 128; ++i) add(fmt::format("output_bit_register_{}", i), T::Bool);
  return table.fields;
}

std::vector<FieldInfo> make_input_fields() {
  FieldTable table;
  auto add = [&](std::string name, DataType t) { table.add(std::move(name), t); };
  using T = DataType;
  add("speed_slider_mask", T::Uint32);
  add("speed_slider_fraction", T::Double);
  for (const char* n : {"standard_digital_output_mask", "standard_digital_output", "configurable_digital_output_mask",
                        "configurable_digital_output", "tool_digital_output_mask", "tool_digital_output",
                        "standard_analog_output_mask", "standard_analog_output_type"})
    add(n, T::Uint8);
  add("standard_analog_output_0", T::Double);
  add("standard_analog_output_1", T::Double);
  add("external_force_torque", T::Vector6d);
  for (int i = 0; i < 48; ++i) add(fmt::format("input_int_register_{}", i), T::Int32);
  for (int i = 0; i < 48; ++i) add(fmt::format("input_double_register_{}", i), T::Double);
  for (int i = 64; i < 128; ++i) add(fmt::format("input_bit_register_{}", i), T::Bool);
  return table.fields;
}

const FieldInfo* find_in(const std::vector<FieldInfo>& fields, std::string_view name) {
  static const auto index = [](const std::vector<FieldInfo>& v) {
    std::unordered_map<std::string_view, const FieldInfo*> m;
    for (const auto& f : v) m.emplace(f.name, &f);
    return m;
  };
  static const auto out_index = index(output_fields());
  static const auto in_index = index(input_fields());
  const auto& m = &fields == &output_fields() ? out_index : in_index;
  const auto it = m.find(name);
  return it == m.end() ? nullptr : it->second;
}

}  // namespace

// ---- names and types ----------------------------------------------------------------------

std::string package_name(std::uint8_t type) {
  switch (static_cast<PackageType>(type)) {
    case PackageType::RequestProtocolVersion: return "RTDE_REQUEST_PROTOCOL_VERSION";
    case PackageType::GetUrcontrolVersion: return "RTDE_GET_URCONTROL_VERSION";
    case PackageType::TextMessage: return "RTDE_TEXT_MESSAGE";
    case PackageType::DataPackage: return "RTDE_DATA_PACKAGE";
    case PackageType::SetupOutputs: return "RTDE_CONTROL_PACKAGE_SETUP_OUTPUTS";
    case PackageType::SetupInputs: return "RTDE_CONTROL_PACKAGE_SETUP_INPUTS";
    case PackageType::Start: return "RTDE_CONTROL_PACKAGE_START";
    case PackageType::Pause: return "RTDE_CONTROL_PACKAGE_PAUSE";
  }
  return fmt::format("unknown package type 0x{:02x}", type);
}

bool is_known_package(std::uint8_t type) { return package_name(type).rfind("RTDE_", 0) == 0; }

std::string_view type_name(DataType t) {
  switch (t) {
    case DataType::Bool: return "BOOL";
    case DataType::Uint8: return "UINT8";
    case DataType::Uint32: return "UINT32";
    case DataType::Uint64: return "UINT64";
    case DataType::Int32: return "INT32";
    case DataType::Double: return "DOUBLE";
    case DataType::Vector3d: return "VECTOR3D";
    case DataType::Vector6d: return "VECTOR6D";
    case DataType::Vector6Int32: return "VECTOR6INT32";
    case DataType::Vector6Uint32: return "VECTOR6UINT32";
  }
  return "?";
}

bool parse_type(std::string_view s, DataType& out) {
  static const DataType all[] = {DataType::Bool,     DataType::Uint8,    DataType::Uint32,       DataType::Uint64,
                                 DataType::Int32,    DataType::Double,   DataType::Vector3d,     DataType::Vector6d,
                                 DataType::Vector6Int32, DataType::Vector6Uint32};
  for (DataType t : all)
    if (type_name(t) == s) {
      out = t;
      return true;
    }
  return false;
}

int wire_size(DataType t) {
  switch (t) {
    case DataType::Bool:
    case DataType::Uint8: return 1;
    case DataType::Uint32:
    case DataType::Int32: return 4;
    case DataType::Uint64:
    case DataType::Double: return 8;
    case DataType::Vector3d: return 24;
    case DataType::Vector6d: return 48;
    case DataType::Vector6Int32:
    case DataType::Vector6Uint32: return 24;
  }
  return 0;
}

int value_count(DataType t) {
  switch (t) {
    case DataType::Vector3d: return 3;
    case DataType::Vector6d:
    case DataType::Vector6Int32:
    case DataType::Vector6Uint32: return 6;
    default: return 1;
  }
}

std::string_view level_name(MessageLevel l) {
  switch (l) {
    case MessageLevel::Exception: return "EXCEPTION";
    case MessageLevel::Error: return "ERROR";
    case MessageLevel::Warning: return "WARNING";
    case MessageLevel::Info: return "INFO";
  }
  return "?";
}

const std::vector<FieldInfo>& output_fields() {
  static const std::vector<FieldInfo> f = make_output_fields();
  return f;
}
const std::vector<FieldInfo>& input_fields() {
  static const std::vector<FieldInfo> f = make_input_fields();
  return f;
}
const FieldInfo* find_output_field(std::string_view name) { return find_in(output_fields(), name); }
const FieldInfo* find_input_field(std::string_view name) { return find_in(input_fields(), name); }
int frame_scalars() {
  const auto& f = output_fields();
  return f.back().slot + value_count(f.back().type);
}

std::vector<std::string> split_names(std::string_view list) {
  std::vector<std::string> out;
  if (list.empty()) return out;
  std::size_t b = 0;
  while (true) {
    const std::size_t e = list.find(',', b);
    out.emplace_back(list.substr(b, e == std::string_view::npos ? std::string_view::npos : e - b));
    if (e == std::string_view::npos) break;
    b = e + 1;
  }
  if (!out.empty() && out.back().empty()) out.pop_back();  // "a,b," (ur_rtde, fact sheet §10)
  return out;
}

std::string join_names(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

// ---- encoders -----------------------------------------------------------------------------

void encode_request_protocol_version(Bytes& out, std::uint16_t version) {
  const auto at = begin(out, PackageType::RequestProtocolVersion);
  put16(out, version);
  finish(out, at);
}
void encode_get_urcontrol_version(Bytes& out) { finish(out, begin(out, PackageType::GetUrcontrolVersion)); }
void encode_setup_outputs(Bytes& out, int protocol, double frequency, const std::vector<std::string>& names) {
  const auto at = begin(out, PackageType::SetupOutputs);
  if (protocol >= 2) {
    out.resize(out.size() + 8);
    putd(out.data() + out.size() - 8, frequency);
  }
  put_text(out, join_names(names));
  finish(out, at);
}
void encode_setup_inputs(Bytes& out, const std::vector<std::string>& names) {
  const auto at = begin(out, PackageType::SetupInputs);
  put_text(out, join_names(names));
  finish(out, at);
}
void encode_start(Bytes& out) { finish(out, begin(out, PackageType::Start)); }
void encode_pause(Bytes& out) { finish(out, begin(out, PackageType::Pause)); }

void encode_protocol_version_reply(Bytes& out, bool accepted) { encode_accepted_reply(out, PackageType::RequestProtocolVersion, accepted); }
void encode_urcontrol_version_reply(Bytes& out, const ControllerVersion& v) {
  const auto at = begin(out, PackageType::GetUrcontrolVersion);
  out.resize(out.size() + 16);
  std::uint8_t* p = out.data() + out.size() - 16;
  put32(p, v.major);
  put32(p + 4, v.minor);
  put32(p + 8, v.bugfix);
  put32(p + 12, v.build);
  finish(out, at);
}
void encode_setup_reply(Bytes& out, PackageType type, int protocol, std::uint8_t recipe_id,
                        const std::vector<std::string>& types) {
  const auto at = begin(out, type);
  // v1 output replies carry no recipe id; input replies always do (fact sheet §3, §4)
  if (protocol >= 2 || type == PackageType::SetupInputs) put8(out, recipe_id);
  put_text(out, join_names(types));
  finish(out, at);
}
void encode_accepted_reply(Bytes& out, PackageType type, bool accepted) {
  const auto at = begin(out, type);
  put8(out, accepted ? 1 : 0);
  finish(out, at);
}
void encode_text_message(Bytes& out, int protocol, const TextMessage& m) {
  const auto at = begin(out, PackageType::TextMessage);
  if (protocol >= 2) {
    const std::string_view msg = std::string_view(m.message).substr(0, 255);
    const std::string_view src = std::string_view(m.source).substr(0, 255);
    put8(out, static_cast<std::uint8_t>(msg.size()));
    put_text(out, msg);
    put8(out, static_cast<std::uint8_t>(src.size()));
    put_text(out, src);
    put8(out, static_cast<std::uint8_t>(m.level));
  } else {
    put8(out, static_cast<std::uint8_t>(m.level));
    put_text(out, m.message);
  }
  finish(out, at);
}

// ---- decoders -----------------------------------------------------------------------------

std::uint16_t decode_request_protocol_version(const Package& p) {
  expect_size(p, 2, "uint16 protocol version");
  return be16(p.payload.data());
}

bool decode_accepted_reply(const Package& p) {
  expect_size(p, 1, "uint8 accepted");
  const std::uint8_t a = p.payload[0];
  if (a > 1) throw ProtocolError(fmt::format("{}: accepted must be 0 or 1, got {}", package_name(p.type), a));
  return a == 1;
}

ControllerVersion decode_urcontrol_version_reply(const Package& p) {
  expect_size(p, 16, "uint32 major, minor, bugfix, build");
  const std::uint8_t* d = p.payload.data();
  return {be32(d), be32(d + 4), be32(d + 8), be32(d + 12)};
}

SetupRequest decode_setup_outputs(const Package& p, int protocol) {
  SetupRequest r;
  std::span<const std::uint8_t> rest = p.payload;
  if (protocol >= 2) {
    if (rest.size() < 8)
      throw ProtocolError(fmt::format("{}: expected a double frequency (8 bytes) before the names, got {} bytes",
                                      package_name(p.type), rest.size()));
    r.frequency = bed(rest.data());
    rest = rest.subspan(8);
  }
  if (rest.size() > kMaxNameListBytes)
    throw ProtocolError(fmt::format("{}: name list of {} bytes, at most {} allowed", package_name(p.type), rest.size(),
                                    kMaxNameListBytes));
  r.names = split_names(printable(rest));
  return r;
}

SetupRequest decode_setup_inputs(const Package& p) {
  if (p.payload.size() > kMaxNameListBytes)
    throw ProtocolError(fmt::format("{}: name list of {} bytes, at most {} allowed", package_name(p.type),
                                    p.payload.size(), kMaxNameListBytes));
  return {0.0, split_names(printable(p.payload))};
}

SetupReply decode_setup_reply(const Package& p, int protocol) {
  SetupReply r;
  std::span<const std::uint8_t> rest = p.payload;
  if (protocol >= 2 || p.type == static_cast<std::uint8_t>(PackageType::SetupInputs)) {
    if (rest.empty()) throw ProtocolError(fmt::format("{}: expected a recipe id, got an empty payload", package_name(p.type)));
    r.recipe_id = rest[0];
    rest = rest.subspan(1);
  }
  r.types = split_names(printable(rest));
  return r;
}

TextMessage decode_text_message(const Package& p, int protocol) {
  TextMessage m;
  const auto& d = p.payload;
  auto level = [&](std::uint8_t l) {
    if (l > 3) throw ProtocolError(fmt::format("RTDE_TEXT_MESSAGE: level must be 0..3, got {}", l));
    return static_cast<MessageLevel>(l);
  };
  auto text = [](std::span<const std::uint8_t> s) {
    std::string out(s.begin(), s.end());
    for (char& c : out)
      if (static_cast<unsigned char>(c) < 0x20 && c != '\n' && c != '\t') c = '?';  // keep logs printable
    return out;
  };
  if (protocol >= 2) {
    if (d.empty()) throw ProtocolError("RTDE_TEXT_MESSAGE: empty payload, expected uint8 message length");
    const std::size_t ml = d[0];
    if (d.size() < 1 + ml + 1)
      throw ProtocolError(fmt::format("RTDE_TEXT_MESSAGE: message length {} runs past the {}-byte payload", ml, d.size()));
    const std::size_t sl = d[1 + ml];
    if (d.size() != 1 + ml + 1 + sl + 1)
      throw ProtocolError(fmt::format("RTDE_TEXT_MESSAGE: lengths {} + {} imply a {}-byte payload, got {}", ml, sl,
                                      ml + sl + 3, d.size()));
    m.message = text(d.subspan(1, ml));
    m.source = text(d.subspan(2 + ml, sl));
    m.level = level(d[d.size() - 1]);
  } else {
    if (d.empty()) throw ProtocolError("RTDE_TEXT_MESSAGE: empty payload, expected uint8 level");
    m.level = level(d[0]);
    m.message = text(d.subspan(1));
  }
  return m;
}

// ---- framing ------------------------------------------------------------------------------

void Framer::feed(const std::uint8_t* data, std::size_t n) {
  if (pos_ > 0 && pos_ == buf_.size()) {
    buf_.clear();
    pos_ = 0;
  } else if (pos_ > 65536) {  // compact now and then; packages returned earlier are no longer referenced
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<long>(pos_));
    pos_ = 0;
  }
  buf_.insert(buf_.end(), data, data + n);
}

bool Framer::next(Package& out) {
  if (buf_.size() - pos_ < 3) return false;
  const std::uint8_t* h = buf_.data() + pos_;
  const std::size_t size = be16(h);
  if (size < 3)
    throw ProtocolError(fmt::format("package size field is {} (smaller than the 3-byte header); stream is corrupt", size));
  if (size > kMaxPackageSize)
    throw ProtocolError(fmt::format("package size field is {} bytes (type 0x{:02x}), larger than the {}-byte limit; "
                                    "stream is corrupt or not RTDE",
                                    size, h[2], kMaxPackageSize));
  if (buf_.size() - pos_ < size) return false;
  out.type = h[2];
  out.payload = std::span<const std::uint8_t>(h + 3, size - 3);
  pos_ += size;
  return true;
}

// ---- recipes ------------------------------------------------------------------------------

OutputRecipe OutputRecipe::from_reply(std::vector<std::string> names, const SetupReply& reply, int protocol) {
  if (reply.types.size() != names.size())
    throw ProtocolError(fmt::format("RTDE_CONTROL_PACKAGE_SETUP_OUTPUTS: {} names requested, {} types returned",
                                    names.size(), reply.types.size()));
  std::vector<std::string> not_found, in_use, bad;
  OutputRecipe r;
  r.id = reply.recipe_id;
  r.protocol = protocol;
  int off = protocol >= 2 ? 1 : 0;
  for (std::size_t i = 0; i < names.size(); ++i) {
    DataType t;
    if (reply.types[i] == "NOT_FOUND") not_found.push_back(names[i]);
    else if (reply.types[i] == "IN_USE") in_use.push_back(names[i]);
    else if (!parse_type(reply.types[i], t)) bad.push_back(fmt::format("{} ({})", names[i], reply.types[i]));
    else {
      r.types.push_back(t);
      r.offsets.push_back(off);
      r.value_index.push_back(r.values);
      off += wire_size(t);
      r.values += value_count(t);
    }
  }
  std::string err;
  if (!not_found.empty()) err += fmt::format("the controller does not know {} (NOT_FOUND)", join_names(not_found));
  if (!in_use.empty()) err += fmt::format("{}{} already in use (IN_USE)", err.empty() ? "" : "; ", join_names(in_use));
  if (!bad.empty()) err += fmt::format("{}unknown type for {}", err.empty() ? "" : "; ", join_names(bad));
  if (!err.empty()) throw ProtocolError(err);
  r.names = std::move(names);
  r.payload_size = off;
  return r;
}

int OutputRecipe::index_of(std::string_view name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

void decode_data_package(const Package& p, const OutputRecipe& r, double* v) {
  if (static_cast<int>(p.payload.size()) != r.payload_size)
    throw ProtocolError(fmt::format("RTDE_DATA_PACKAGE: expected {} payload bytes for recipe {} ({} fields), got {}",
                                    r.payload_size, r.id, r.names.size(), p.payload.size()));
  const std::uint8_t* d = p.payload.data();
  if (r.protocol >= 2 && d[0] != r.id)
    throw ProtocolError(fmt::format("RTDE_DATA_PACKAGE: recipe id {} does not match the set-up recipe {}", d[0], r.id));
  const std::size_t n = r.types.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* s = d + r.offsets[i];
    double* o = v + r.value_index[i];
    switch (r.types[i]) {
      case DataType::Bool:
      case DataType::Uint8: o[0] = s[0]; break;
      case DataType::Uint32: o[0] = be32(s); break;
      case DataType::Int32: o[0] = static_cast<std::int32_t>(be32(s)); break;
      case DataType::Uint64: o[0] = static_cast<double>(be64(s)); break;
      case DataType::Double: o[0] = bed(s); break;
      case DataType::Vector3d:
        for (int k = 0; k < 3; ++k) o[k] = bed(s + 8 * k);
        break;
      case DataType::Vector6d:
        for (int k = 0; k < 6; ++k) o[k] = bed(s + 8 * k);
        break;
      case DataType::Vector6Int32:
        for (int k = 0; k < 6; ++k) o[k] = static_cast<std::int32_t>(be32(s + 4 * k));
        break;
      case DataType::Vector6Uint32:
        for (int k = 0; k < 6; ++k) o[k] = be32(s + 4 * k);
        break;
    }
  }
}

void encode_data_package(Bytes& out, int protocol, const ServerRecipe& r, const double* frame) {
  const auto at = begin(out, PackageType::DataPackage);
  if (protocol >= 2) put8(out, r.id);
  std::size_t pos = out.size();
  int bytes = 0;
  for (const FieldInfo* f : r.fields) bytes += wire_size(f->type);
  out.resize(pos + static_cast<std::size_t>(bytes));
  std::uint8_t* p = out.data() + pos;
  for (const FieldInfo* f : r.fields) {
    const double* v = frame + f->slot;
    switch (f->type) {
      case DataType::Bool: *p = v[0] != 0.0 ? 1 : 0; break;
      case DataType::Uint8: *p = static_cast<std::uint8_t>(v[0]); break;
      case DataType::Uint32: put32(p, static_cast<std::uint32_t>(v[0])); break;
      case DataType::Int32: put32(p, static_cast<std::uint32_t>(static_cast<std::int32_t>(v[0]))); break;
      case DataType::Uint64: put64(p, static_cast<std::uint64_t>(v[0])); break;
      case DataType::Double: putd(p, v[0]); break;
      case DataType::Vector3d:
        for (int k = 0; k < 3; ++k) putd(p + 8 * k, v[k]);
        break;
      case DataType::Vector6d:
        for (int k = 0; k < 6; ++k) putd(p + 8 * k, v[k]);
        break;
      case DataType::Vector6Int32:
        for (int k = 0; k < 6; ++k) put32(p + 4 * k, static_cast<std::uint32_t>(static_cast<std::int32_t>(v[k])));
        break;
      case DataType::Vector6Uint32:
        for (int k = 0; k < 6; ++k) put32(p + 4 * k, static_cast<std::uint32_t>(v[k]));
        break;
    }
    p += wire_size(f->type);
  }
  finish(out, at);
}

}  // namespace twinwatch::device::rtde
