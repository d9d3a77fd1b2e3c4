#pragma once
/// @file rtde_protocol.hpp
/// Universal Robots RTDE wire format, both directions, without sockets: framing, every package
/// type's encoder and decoder, the output field table, and compiled recipes. The client
/// (rtde_client.hpp) and the virtual controller (rtde_server.hpp) are built on it, and the fuzz
/// target (fuzz/rtde_fuzz.cpp) drives it directly.
///
/// Facts and their sources: ../shared/reference/rtde-protocol.md (cited below as "fact sheet §N").
///  - a package is `uint16 size | uint8 type | payload`, size counts the header (§2);
///  - all numbers are big-endian (§1);
///  - protocol v2 adds the output frequency to SETUP_OUTPUTS, a recipe id to its reply and to
///    every output DATA_PACKAGE, and length-prefixed text messages (§4).
///
/// Decoders throw rtde::ProtocolError with a message that names the package type, the field,
/// what was expected and what arrived; they never read past the package they are given.
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace twinwatch::device::rtde {

inline constexpr std::uint16_t kDefaultPort = 30004;
inline constexpr int kMaxProtocolVersion = 2;
/// Largest package we accept. The size field allows 65535; a real recipe is far smaller (names
/// ≤ 2048 bytes, fact sheet §6), so anything larger is treated as garbage on the stream.
inline constexpr std::size_t kMaxPackageSize = 16384;
/// The recipe name list may be at most 2048 bytes (fact sheet §6).
inline constexpr std::size_t kMaxNameListBytes = 2048;

enum class PackageType : std::uint8_t {
  RequestProtocolVersion = 'V',
  GetUrcontrolVersion = 'v',
  TextMessage = 'M',
  DataPackage = 'U',
  SetupOutputs = 'O',
  SetupInputs = 'I',
  Start = 'S',
  Pause = 'P',
};
/// "RTDE_REQUEST_PROTOCOL_VERSION" etc.; "unknown (0xNN)" for other codes.
std::string package_name(std::uint8_t type);
bool is_known_package(std::uint8_t type);

enum class DataType : std::uint8_t { Bool, Uint8, Uint32, Uint64, Int32, Double, Vector3d, Vector6d, Vector6Int32, Vector6Uint32 };
std::string_view type_name(DataType t);        ///< "VECTOR6D" ...
bool parse_type(std::string_view s, DataType& out);  ///< false for NOT_FOUND, IN_USE and unknown strings
int wire_size(DataType t);                     ///< bytes on the wire
int value_count(DataType t);                   ///< scalars (3 for VECTOR3D, 6 for VECTOR6*)

/// A malformed or unexpected package.
class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// ---- output fields ------------------------------------------------------------------------

/// One controller output: its RTDE name, type, and where its scalars live in a ControllerFrame.
struct FieldInfo {
  std::string name;
  DataType type;
  int slot;  ///< index of the first scalar in a frame
};
/// The output names a UR e-Series controller serves (fact sheet §9), with their types; general
/// purpose registers included. Order is fixed; slots are contiguous.
const std::vector<FieldInfo>& output_fields();
const FieldInfo* find_output_field(std::string_view name);  ///< nullptr if unknown
int frame_scalars();                                        ///< scalars in a full frame
/// The input names the virtual controller accepts in SETUP_INPUTS (fact sheet §9 "Inputs").
const std::vector<FieldInfo>& input_fields();
const FieldInfo* find_input_field(std::string_view name);

/// Splits a comma-separated name list; an empty last name (trailing comma, as ur_rtde sends)
/// is dropped, spaces around names are kept as-is except that an all-empty list gives {}.
std::vector<std::string> split_names(std::string_view list);
std::string join_names(const std::vector<std::string>& names);

// ---- packages -----------------------------------------------------------------------------

struct ControllerVersion {
  std::uint32_t major = 0, minor = 0, bugfix = 0, build = 0;
};

enum class MessageLevel : std::uint8_t { Exception = 0, Error = 1, Warning = 2, Info = 3 };
struct TextMessage {
  MessageLevel level = MessageLevel::Info;
  std::string message;
  std::string source;  ///< v2 only
};
std::string_view level_name(MessageLevel l);

/// A complete package cut from the stream; `payload` points into the framer's buffer and is
/// valid until the next call to Framer::next().
struct Package {
  std::uint8_t type = 0;
  std::span<const std::uint8_t> payload;
};

using Bytes = std::vector<std::uint8_t>;

// Encoders append one package to `out`. Client → controller:
void encode_request_protocol_version(Bytes& out, std::uint16_t version);
void encode_get_urcontrol_version(Bytes& out);
/// v2: `double frequency` then names; v1: names only (frequency ignored).
void encode_setup_outputs(Bytes& out, int protocol, double frequency, const std::vector<std::string>& names);
void encode_setup_inputs(Bytes& out, const std::vector<std::string>& names);
void encode_start(Bytes& out);
void encode_pause(Bytes& out);
// Controller → client:
void encode_protocol_version_reply(Bytes& out, bool accepted);
void encode_urcontrol_version_reply(Bytes& out, const ControllerVersion& v);
/// v2: recipe id + types; v1: types only.
void encode_setup_reply(Bytes& out, PackageType type, int protocol, std::uint8_t recipe_id,
                        const std::vector<std::string>& types);
void encode_accepted_reply(Bytes& out, PackageType type, bool accepted);  ///< START / PAUSE reply
// Both directions: v1 `uint8 level | text`, v2 `uint8 len | msg | uint8 len | source | uint8 level`.
void encode_text_message(Bytes& out, int protocol, const TextMessage& m);

// Decoders (payload of a package of the matching type):
std::uint16_t decode_request_protocol_version(const Package& p);
bool decode_accepted_reply(const Package& p);  ///< V, S and P replies
ControllerVersion decode_urcontrol_version_reply(const Package& p);
struct SetupRequest {
  double frequency = 0.0;  ///< v2 outputs only
  std::vector<std::string> names;
};
SetupRequest decode_setup_outputs(const Package& p, int protocol);
SetupRequest decode_setup_inputs(const Package& p);
struct SetupReply {
  std::uint8_t recipe_id = 0;
  std::vector<std::string> types;  ///< as sent: "DOUBLE", "NOT_FOUND", "IN_USE", ...
};
SetupReply decode_setup_reply(const Package& p, int protocol);
TextMessage decode_text_message(const Package& p, int protocol);

// ---- framing ------------------------------------------------------------------------------

/// Cuts a byte stream into packages. Feed whatever recv() returned; call next() until it
/// returns false. A size field < 3 or > kMaxPackageSize cannot be resynchronised on a TCP
/// stream, so next() throws ProtocolError and the owner closes the connection (the packages
/// already returned stay valid data).
class Framer {
 public:
  void feed(const std::uint8_t* data, std::size_t n);
  bool next(Package& out);
  std::size_t buffered() const { return buf_.size() - pos_; }
  void clear() {
    buf_.clear();
    pos_ = 0;
  }

 private:
  Bytes buf_;
  std::size_t pos_ = 0;
};

// ---- recipes and data packages --------------------------------------------------------------

/// An output recipe as the client sees it after SETUP_OUTPUTS: names, their types and the
/// byte layout of a data package.
struct OutputRecipe {
  std::uint8_t id = 0;
  int protocol = 2;
  std::vector<std::string> names;
  std::vector<DataType> types;
  std::vector<int> offsets;    ///< byte offset of each field's value in the payload
  std::vector<int> value_index;  ///< index of each field's first scalar in a decoded value array
  int payload_size = 0;        ///< payload bytes of a data package (recipe id included in v2)
  int values = 0;              ///< scalars in a decoded package

  /// Builds the layout. Throws ProtocolError if a type string is not a data type; the message
  /// lists every name answered NOT_FOUND (or IN_USE) by name.
  static OutputRecipe from_reply(std::vector<std::string> names, const SetupReply& reply, int protocol);
  int index_of(std::string_view name) const;  ///< field index or -1
};

/// Decodes an output data package into `values` (recipe.values scalars, converted to double:
/// integers up to 2^53 are exact, which covers every RTDE integer output in practice — the
/// bit fields use the low 32 bits). Throws ProtocolError on a size or recipe-id mismatch.
void decode_data_package(const Package& p, const OutputRecipe& recipe, double* values);

/// The controller side of a recipe: which frame slots to send, and how.
struct ServerRecipe {
  std::uint8_t id = 0;
  std::vector<const FieldInfo*> fields;
  int payload_size = 0;
};
/// Appends one output data package built from a full frame (frame_scalars() doubles).
void encode_data_package(Bytes& out, int protocol, const ServerRecipe& recipe, const double* frame);

}  // namespace twinwatch::device::rtde
