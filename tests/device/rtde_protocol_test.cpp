// RTDE wire format: byte-exact fixtures for every package type in both directions, framing, and
// the virtual controller's session logic. The fixture bytes are written out by hand from the fact
// sheet (../shared/reference/rtde-protocol.md §2–§8), not produced by our encoder.
#include <gtest/gtest.h>

#include <cstring>

#include "twinwatch/device/rtde_protocol.hpp"
#include "twinwatch/device/rtde_server.hpp"

namespace rtde = twinwatch::device::rtde;
using rtde::Bytes;
using rtde::PackageType;

namespace {

Bytes ascii(const char* s) { return Bytes(s, s + std::strlen(s)); }
Bytes cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

// Cuts exactly one package out of `bytes` (and checks nothing is left over).
rtde::Package one_package(const Bytes& bytes, rtde::Framer& f) {
  f.clear();
  f.feed(bytes.data(), bytes.size());
  rtde::Package p;
  EXPECT_TRUE(f.next(p));
  EXPECT_EQ(f.buffered(), 0u);
  return p;
}

}  // namespace

// ---- client → controller --------------------------------------------------------------------

TEST(RtdeFixtures, RequestProtocolVersion) {
  const Bytes wire{0x00, 0x05, 'V', 0x00, 0x02};  // size 5 = header 3 + uint16
  Bytes out;
  rtde::encode_request_protocol_version(out, 2);
  EXPECT_EQ(out, wire);
  rtde::Framer f;
  const auto p = one_package(wire, f);
  EXPECT_EQ(p.type, 'V');
  EXPECT_EQ(rtde::decode_request_protocol_version(p), 2);
}

TEST(RtdeFixtures, GetUrcontrolVersion) {
  const Bytes wire{0x00, 0x03, 'v'};
  Bytes out;
  rtde::encode_get_urcontrol_version(out);
  EXPECT_EQ(out, wire);
}

TEST(RtdeFixtures, SetupOutputsV2CarriesTheFrequencyAsBigEndianDouble) {
  // 500.0 = 0x407F400000000000; names are the rest of the package, no terminator
  const Bytes wire = cat({{0x00, 0x1d, 'O', 0x40, 0x7f, 0x40, 0x00, 0x00, 0x00, 0x00, 0x00}, ascii("timestamp,actual_q")});
  Bytes out;
  rtde::encode_setup_outputs(out, 2, 500.0, {"timestamp", "actual_q"});
  EXPECT_EQ(out, wire);
  rtde::Framer f;
  const auto req = rtde::decode_setup_outputs(one_package(wire, f), 2);
  EXPECT_EQ(req.frequency, 500.0);
  EXPECT_EQ(req.names, (std::vector<std::string>{"timestamp", "actual_q"}));
}

TEST(RtdeFixtures, SetupOutputsV1HasNoFrequency) {
  const Bytes wire = cat({{0x00, 0x15, 'O'}, ascii("timestamp,actual_q")});
  Bytes out;
  rtde::encode_setup_outputs(out, 1, 500.0, {"timestamp", "actual_q"});
  EXPECT_EQ(out, wire);
  rtde::Framer f;
  EXPECT_EQ(rtde::decode_setup_outputs(one_package(wire, f), 1).names.size(), 2u);
}

TEST(RtdeFixtures, SetupInputs) {
  const Bytes wire = cat({{0x00, 0x14, 'I'}, ascii("speed_slider_mask")});
  Bytes out;
  rtde::encode_setup_inputs(out, {"speed_slider_mask"});
  EXPECT_EQ(out, wire);
  rtde::Framer f;
  EXPECT_EQ(rtde::decode_setup_inputs(one_package(wire, f)).names, std::vector<std::string>{"speed_slider_mask"});
}

TEST(RtdeFixtures, StartAndPause) {
  Bytes out;
  rtde::encode_start(out);
  EXPECT_EQ(out, (Bytes{0x00, 0x03, 'S'}));
  out.clear();
  rtde::encode_pause(out);
  EXPECT_EQ(out, (Bytes{0x00, 0x03, 'P'}));
}

TEST(RtdeFixtures, InputDataPackageIsCheckedAgainstItsRecipe) {
  rtde::ServerSession s({5, 23, 0, 0}, 500.0);
  Bytes in, out;
  rtde::encode_setup_inputs(in, {"speed_slider_mask"});
  s.on_bytes(in.data(), in.size(), out);
  ASSERT_EQ(out, cat({{0x00, 0x0a, 'I', 0x01}, ascii("UINT32")}));  // recipe id 1, one type
  // recipe 1 + UINT32 1: accepted silently
  const Bytes good{0x00, 0x08, 'U', 0x01, 0x00, 0x00, 0x00, 0x01};
  out.clear();
  s.on_bytes(good.data(), good.size(), out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(s.errors(), 0);
  // one byte short: an ERROR text message, the session carries on
  const Bytes short_pkg{0x00, 0x07, 'U', 0x01, 0x00, 0x00, 0x00};
  out.clear();
  s.on_bytes(short_pkg.data(), short_pkg.size(), out);
  EXPECT_EQ(s.errors(), 1);
  rtde::Framer f;
  const auto msg = rtde::decode_text_message(one_package(out, f), 2);
  EXPECT_EQ(msg.level, rtde::MessageLevel::Error);
  EXPECT_NE(msg.message.find("needs 5 payload bytes, got 4"), std::string::npos) << msg.message;
}

// ---- controller → client --------------------------------------------------------------------

TEST(RtdeFixtures, ProtocolVersionReply) {
  Bytes out;
  rtde::encode_protocol_version_reply(out, true);
  EXPECT_EQ(out, (Bytes{0x00, 0x04, 'V', 0x01}));
  rtde::Framer f;
  EXPECT_FALSE(rtde::decode_accepted_reply(one_package(Bytes{0x00, 0x04, 'V', 0x00}, f)));
}

TEST(RtdeFixtures, UrcontrolVersionReply) {
  const Bytes wire{0x00, 0x13, 'v', 0, 0, 0, 5, 0, 0, 0, 23, 0, 0, 0, 1, 0, 0, 0x30, 0x39};
  Bytes out;
  rtde::encode_urcontrol_version_reply(out, {5, 23, 1, 12345});
  EXPECT_EQ(out, wire);
  rtde::Framer f;
  const auto v = rtde::decode_urcontrol_version_reply(one_package(wire, f));
  EXPECT_EQ(v.major, 5u);
  EXPECT_EQ(v.minor, 23u);
  EXPECT_EQ(v.bugfix, 1u);
  EXPECT_EQ(v.build, 12345u);
}

TEST(RtdeFixtures, SetupOutputsReplyV2AndV1) {
  const Bytes v2 = cat({{0x00, 0x13, 'O', 0x01}, ascii("DOUBLE,VECTOR6D")});
  const Bytes v1 = cat({{0x00, 0x12, 'O'}, ascii("DOUBLE,VECTOR6D")});
  Bytes out;
  rtde::encode_setup_reply(out, PackageType::SetupOutputs, 2, 1, {"DOUBLE", "VECTOR6D"});
  EXPECT_EQ(out, v2);
  out.clear();
  rtde::encode_setup_reply(out, PackageType::SetupOutputs, 1, 1, {"DOUBLE", "VECTOR6D"});
  EXPECT_EQ(out, v1);
  rtde::Framer f;
  const auto r2 = rtde::decode_setup_reply(one_package(v2, f), 2);
  EXPECT_EQ(r2.recipe_id, 1);
  EXPECT_EQ(r2.types, (std::vector<std::string>{"DOUBLE", "VECTOR6D"}));
  const auto r1 = rtde::decode_setup_reply(one_package(v1, f), 1);
  EXPECT_EQ(r1.types.size(), 2u);
}

TEST(RtdeFixtures, StartPauseReplies) {
  Bytes out;
  rtde::encode_accepted_reply(out, PackageType::Start, true);
  rtde::encode_accepted_reply(out, PackageType::Pause, false);
  EXPECT_EQ(out, (Bytes{0x00, 0x04, 'S', 0x01, 0x00, 0x04, 'P', 0x00}));
}

TEST(RtdeFixtures, TextMessageV2AndV1) {
  const Bytes v2{0x00, 0x0a, 'M', 0x02, 'h', 'i', 0x02, 't', 'w', 0x03};  // len msg len src level
  const Bytes v1{0x00, 0x06, 'M', 0x01, 'h', 'i'};                        // level msg
  Bytes out;
  rtde::encode_text_message(out, 2, {rtde::MessageLevel::Info, "hi", "tw"});
  EXPECT_EQ(out, v2);
  out.clear();
  rtde::encode_text_message(out, 1, {rtde::MessageLevel::Error, "hi", ""});
  EXPECT_EQ(out, v1);
  rtde::Framer f;
  const auto m2 = rtde::decode_text_message(one_package(v2, f), 2);
  EXPECT_EQ(m2.message, "hi");
  EXPECT_EQ(m2.source, "tw");
  EXPECT_EQ(m2.level, rtde::MessageLevel::Info);
  const auto m1 = rtde::decode_text_message(one_package(v1, f), 1);
  EXPECT_EQ(m1.message, "hi");
  EXPECT_EQ(m1.level, rtde::MessageLevel::Error);
}

TEST(RtdeFixtures, OutputDataPackageV2AndV1) {
  // timestamp DOUBLE 1.5, robot_mode INT32 -1, actual_digital_output_bits UINT64 5
  const Bytes v2{0x00, 0x18, 'U', 0x01, 0x3f, 0xf8, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0xff, 0, 0, 0, 0, 0, 0, 0, 0x05};
  const std::vector<std::string> names{"timestamp", "robot_mode", "actual_digital_output_bits"};
  const std::vector<std::string> types{"DOUBLE", "INT32", "UINT64"};
  const auto recipe = rtde::OutputRecipe::from_reply(names, {1, types}, 2);
  EXPECT_EQ(recipe.payload_size, 21);
  rtde::Framer f;
  double v[3];
  rtde::decode_data_package(one_package(v2, f), recipe, v);
  EXPECT_EQ(v[0], 1.5);
  EXPECT_EQ(v[1], -1.0);
  EXPECT_EQ(v[2], 5.0);

  // the server encodes the same bytes from a frame
  std::vector<double> frame(static_cast<std::size_t>(rtde::frame_scalars()), 0.0);
  frame[static_cast<std::size_t>(rtde::find_output_field("timestamp")->slot)] = 1.5;
  frame[static_cast<std::size_t>(rtde::find_output_field("robot_mode")->slot)] = -1;
  frame[static_cast<std::size_t>(rtde::find_output_field("actual_digital_output_bits")->slot)] = 5;
  rtde::ServerRecipe sr;
  sr.id = 1;
  for (const auto& n : names) sr.fields.push_back(rtde::find_output_field(n));
  Bytes out;
  rtde::encode_data_package(out, 2, sr, frame.data());
  EXPECT_EQ(out, v2);
  out.clear();
  rtde::encode_data_package(out, 1, sr, frame.data());
  Bytes v1{0x00, 0x17, 'U'};
  v1.insert(v1.end(), v2.begin() + 4, v2.end());
  EXPECT_EQ(out, v1);
  const auto recipe1 = rtde::OutputRecipe::from_reply(names, {0, types}, 1);
  rtde::decode_data_package(one_package(v1, f), recipe1, v);
  EXPECT_EQ(v[0], 1.5);
}

TEST(RtdeFixtures, EveryOutputTypeRoundTrips) {
  // one field of every type the controller serves, through encode → frame → decode
  const std::vector<std::string> names{"timestamp", "actual_q", "joint_mode", "robot_mode", "runtime_state",
                                       "actual_digital_input_bits", "payload_cog", "output_bit_register_64"};
  std::vector<double> frame(static_cast<std::size_t>(rtde::frame_scalars()), 0.0);
  rtde::ServerRecipe sr;
  sr.id = 7;
  std::vector<std::string> types;
  double x = 1.0;
  std::vector<double> expect;
  for (const auto& n : names) {
    const auto* fi = rtde::find_output_field(n);
    ASSERT_NE(fi, nullptr) << n;
    sr.fields.push_back(fi);
    types.emplace_back(rtde::type_name(fi->type));
    for (int k = 0; k < rtde::value_count(fi->type); ++k) {
      const double val = fi->type == rtde::DataType::Bool ? 1.0 : (fi->type == rtde::DataType::Vector6Int32 ? -x : x + 0.25 * (fi->type == rtde::DataType::Double || fi->type == rtde::DataType::Vector6d || fi->type == rtde::DataType::Vector3d));
      frame[static_cast<std::size_t>(fi->slot + k)] = val;
      expect.push_back(val);
      x += 1.0;
    }
  }
  EXPECT_EQ(types, (std::vector<std::string>{"DOUBLE", "VECTOR6D", "VECTOR6INT32", "INT32", "UINT32", "UINT64", "VECTOR3D", "BOOL"}));
  Bytes out;
  rtde::encode_data_package(out, 2, sr, frame.data());
  const auto recipe = rtde::OutputRecipe::from_reply(names, {7, types}, 2);
  EXPECT_EQ(static_cast<int>(out.size()), 3 + recipe.payload_size);
  rtde::Framer f;
  std::vector<double> got(static_cast<std::size_t>(recipe.values));
  rtde::decode_data_package(one_package(out, f), recipe, got.data());
  EXPECT_EQ(got, expect);
}

// ---- decoding errors name the package, the field, expected and actual -------------------------

TEST(RtdeErrors, DecodersReportWhatWasExpected) {
  rtde::Framer f;
  try {
    rtde::decode_urcontrol_version_reply(one_package(Bytes{0x00, 0x05, 'v', 0, 5}, f));
    FAIL();
  } catch (const rtde::ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("RTDE_GET_URCONTROL_VERSION"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("16"), std::string::npos) << e.what();
  }
  // a v2 text message whose message length runs past the end
  EXPECT_THROW(rtde::decode_text_message(one_package(Bytes{0x00, 0x06, 'M', 0x09, 'h', 'i'}, f), 2), rtde::ProtocolError);
  // data package of the wrong size / wrong recipe id
  const auto recipe = rtde::OutputRecipe::from_reply({"timestamp"}, {1, {"DOUBLE"}}, 2);
  double v;
  try {
    rtde::decode_data_package(one_package(Bytes{0x00, 0x05, 'U', 0x01, 0x00}, f), recipe, &v);
    FAIL();
  } catch (const rtde::ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("expected 9 payload bytes"), std::string::npos) << e.what();
  }
  EXPECT_THROW(rtde::decode_data_package(one_package(Bytes{0x00, 0x0c, 'U', 0x02, 0, 0, 0, 0, 0, 0, 0, 0}, f), recipe, &v),
               rtde::ProtocolError);
}

TEST(RtdeErrors, NotFoundAndInUseAreReportedByName) {
  try {
    rtde::OutputRecipe::from_reply({"timestamp", "acutal_q", "foo"}, {0, {"DOUBLE", "NOT_FOUND", "NOT_FOUND"}}, 2);
    FAIL();
  } catch (const rtde::ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("acutal_q"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("foo"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("NOT_FOUND"), std::string::npos) << e.what();
  }
  EXPECT_THROW(rtde::OutputRecipe::from_reply({"timestamp"}, {1, {"IN_USE"}}, 2), rtde::ProtocolError);
  EXPECT_THROW(rtde::OutputRecipe::from_reply({"timestamp", "actual_q"}, {1, {"DOUBLE"}}, 2), rtde::ProtocolError);
}

// ---- framing --------------------------------------------------------------------------------

TEST(RtdeFramer, ReassemblesPackagesSplitAtEveryByte) {
  Bytes stream;
  rtde::encode_request_protocol_version(stream, 2);
  rtde::encode_text_message(stream, 2, {rtde::MessageLevel::Warning, "hello", "me"});
  rtde::encode_start(stream);
  for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
    rtde::Framer f;
    std::vector<std::uint8_t> types;
    rtde::Package p;
    f.feed(stream.data(), cut);
    while (f.next(p)) types.push_back(p.type);
    f.feed(stream.data() + cut, stream.size() - cut);
    while (f.next(p)) types.push_back(p.type);
    EXPECT_EQ(types, (std::vector<std::uint8_t>{'V', 'M', 'S'})) << "cut at " << cut;
  }
}

TEST(RtdeFramer, CorruptSizeFieldsThrow) {
  rtde::Framer f;
  const Bytes too_small{0x00, 0x02, 'V'};
  f.feed(too_small.data(), too_small.size());
  rtde::Package p;
  EXPECT_THROW(f.next(p), rtde::ProtocolError);
  rtde::Framer g;
  const Bytes too_big{0xff, 0xff, 'U'};
  g.feed(too_big.data(), too_big.size());
  EXPECT_THROW(g.next(p), rtde::ProtocolError);
}

TEST(RtdeFramer, TruncatedPackageWaitsForTheRest) {
  rtde::Framer f;
  const Bytes part{0x00, 0x05, 'V', 0x00};
  f.feed(part.data(), part.size());
  rtde::Package p;
  EXPECT_FALSE(f.next(p));
  EXPECT_EQ(f.buffered(), 4u);
}

TEST(RtdeNames, TrailingCommaIsIgnored) {
  EXPECT_EQ(rtde::split_names("timestamp,actual_q,"), (std::vector<std::string>{"timestamp", "actual_q"}));
  EXPECT_TRUE(rtde::split_names("").empty());
}

// ---- the virtual controller's session -------------------------------------------------------

namespace {

struct Talk {
  rtde::ServerSession s{{5, 23, 0, 0}, 500.0};
  rtde::Framer f;
  std::vector<rtde::Package> replies;
  Bytes out;

  // Sends bytes, returns the reply packages (copies of their payloads kept in `store`).
  std::vector<std::pair<std::uint8_t, Bytes>> send(const Bytes& in) {
    out.clear();
    s.on_bytes(in.data(), in.size(), out);
    f.feed(out.data(), out.size());
    std::vector<std::pair<std::uint8_t, Bytes>> r;
    rtde::Package p;
    while (f.next(p)) r.emplace_back(p.type, Bytes(p.payload.begin(), p.payload.end()));
    return r;
  }
};

}  // namespace

TEST(RtdeSession, HandshakeLikeUrRtdeWithTrailingCommaAndIgnoredVersionReply) {
  Talk t;
  // ur_rtde sends V2, v and SETUP_OUTPUTS back to back without reading the replies
  Bytes in;
  rtde::encode_request_protocol_version(in, 2);
  rtde::encode_get_urcontrol_version(in);
  Bytes setup{0x00, 0x00, 'O', 0x40, 0x7f, 0x40, 0, 0, 0, 0, 0};
  const Bytes names = ascii("timestamp,actual_q,");
  setup.insert(setup.end(), names.begin(), names.end());
  setup[1] = static_cast<std::uint8_t>(setup.size());
  in.insert(in.end(), setup.begin(), setup.end());
  const auto r = t.send(in);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0], (std::pair<std::uint8_t, Bytes>{'V', {1}}));
  EXPECT_EQ(r[1].first, 'v');
  EXPECT_EQ(r[2].first, 'O');
  EXPECT_EQ(r[2].second, cat({{0x01}, ascii("DOUBLE,VECTOR6D")}));
}

TEST(RtdeSession, RecipeIdsCountAndNotFoundInstallsNothing) {
  Talk t;
  Bytes in;
  rtde::encode_setup_outputs(in, 2, 125.0, {"timestamp"});
  EXPECT_EQ(t.send(in)[0].second[0], 1);
  in.clear();
  rtde::encode_setup_outputs(in, 2, 125.0, {"timestamp", "no_such_thing"});
  const auto r = t.send(in);
  EXPECT_EQ(r[0].second, cat({{0x00}, ascii("DOUBLE,NOT_FOUND")}));
  EXPECT_EQ(t.s.output_recipe()->id, 1);  // the failed setup left recipe 1 in place
  in.clear();
  rtde::encode_setup_outputs(in, 2, 0.0, {"actual_q"});  // 0 Hz = the base rate
  EXPECT_EQ(t.send(in)[0].second[0], 2);
  EXPECT_EQ(t.s.frequency(), 500.0);
}

TEST(RtdeSession, StartPauseStartAndRateDivision) {
  Talk t;
  Bytes in;
  rtde::encode_start(in);
  EXPECT_EQ(t.send(in).back(), (std::pair<std::uint8_t, Bytes>{'S', {0}}));  // no recipe yet
  in.clear();
  rtde::encode_setup_outputs(in, 2, 125.0, {"timestamp"});
  rtde::encode_start(in);
  EXPECT_EQ(t.send(in).back(), (std::pair<std::uint8_t, Bytes>{'S', {1}}));
  std::vector<double> frame(static_cast<std::size_t>(rtde::frame_scalars()), 0.0);
  Bytes out;
  int sent = 0;
  for (int k = 0; k < 500; ++k) sent += t.s.on_cycle(frame.data(), out);
  EXPECT_EQ(sent, 125);  // 125 Hz out of 500 Hz cycles
  in.clear();
  rtde::encode_pause(in);
  EXPECT_EQ(t.send(in).back(), (std::pair<std::uint8_t, Bytes>{'P', {1}}));
  EXPECT_FALSE(t.s.on_cycle(frame.data(), out));
  in.clear();
  rtde::encode_start(in);
  EXPECT_EQ(t.send(in).back(), (std::pair<std::uint8_t, Bytes>{'S', {1}}));
  EXPECT_TRUE(t.s.streaming());
}

TEST(RtdeSession, V1ClientGetsV1Layouts) {
  Talk t;
  Bytes in;
  rtde::encode_request_protocol_version(in, 1);
  rtde::encode_setup_outputs(in, 1, 0.0, {"timestamp"});
  rtde::encode_start(in);
  const auto r = t.send(in);
  EXPECT_EQ(r[1].second, ascii("DOUBLE"));  // no recipe id in v1
  std::vector<double> frame(static_cast<std::size_t>(rtde::frame_scalars()), 0.0);
  Bytes out;
  ASSERT_TRUE(t.s.on_cycle(frame.data(), out));
  EXPECT_EQ(out.size(), 3u + 8u);  // no recipe id in v1 data
  in.clear();
  rtde::encode_request_protocol_version(in, 3);
  EXPECT_EQ(t.send(in).back(), (std::pair<std::uint8_t, Bytes>{'V', {0}}));
}

TEST(RtdeSession, GarbageAndUnknownPackagesGetAnErrorAndTheSessionCarriesOn) {
  Talk t;
  const Bytes unknown{0x00, 0x04, 'Z', 0x00};
  auto r = t.send(unknown);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].first, 'M');
  const Bytes bad_version{0x00, 0x04, 'V', 0x02};  // uint16 expected, 1 byte sent
  r = t.send(bad_version);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[1], (std::pair<std::uint8_t, Bytes>{'V', {0}}));  // answered, so the client does not hang
  Bytes in;
  rtde::encode_request_protocol_version(in, 2);
  EXPECT_EQ(t.send(in).back(), (std::pair<std::uint8_t, Bytes>{'V', {1}}));
  EXPECT_EQ(t.s.errors(), 2);
  // a corrupt size field cannot be resynchronised: the owner must close
  const Bytes corrupt{0x00, 0x01, 0x00};
  Bytes out;
  EXPECT_THROW(t.s.on_bytes(corrupt.data(), corrupt.size(), out), rtde::ProtocolError);
}

TEST(RtdeSession, SetupWhileStreamingIsRefused) {
  Talk t;
  Bytes in;
  rtde::encode_setup_outputs(in, 2, 500.0, {"timestamp"});
  rtde::encode_start(in);
  rtde::encode_setup_outputs(in, 2, 500.0, {"actual_q"});
  const auto r = t.send(in);
  EXPECT_EQ(r.back().first, 'O');
  EXPECT_EQ(r.back().second[0], 0);
  EXPECT_EQ(t.s.output_recipe()->id, 1);
}
