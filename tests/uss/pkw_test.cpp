// The PKW area (C 4): PKE fields, the request and reply id tables (Tabellen 4.1-4.3), IND
// (C 4.2.2), PWE placement (C 4.2.3), the payload codec, reply matching incl. stale replies and
// spontaneous reports (C 4.2.1.2).
#include <gtest/gtest.h>

#include <array>
#include <set>
#include <vector>

#include "uss/pkw.hpp"

namespace liftd::uss {
namespace {

Pkw make(std::uint8_t id, std::uint16_t pnu, std::uint16_t ind = 0, bool toggle = false) {
  Pkw p;
  p.id = id;
  p.pnu = pnu;
  p.ind = ind;
  p.toggle = toggle;
  return p;
}

TEST(UssPke, Fields) {
  // C 4.2.1: AK bits 12..15, toggle bit 11, PNU bits 0..10.
  struct Case {
    std::uint8_t id;
    bool toggle;
    std::uint16_t pnu;
    std::uint16_t pke;
  };
  for (const Case& c :
       {Case{1, false, 52, 0x1034}, Case{15, false, 7, 0xF007}, Case{8, false, 4, 0x8004},
        Case{9, true, 0x7FF, 0x9FFF}, Case{0, true, 0, 0x0800}, Case{12, false, 1000, 0xC3E8}}) {
    Pkw p = make(c.id, c.pnu, 0, c.toggle);
    EXPECT_EQ(p.pke(), c.pke);
    Pkw q;
    q.set_pke(c.pke);
    EXPECT_EQ(q.id, c.id);
    EXPECT_EQ(q.toggle, c.toggle);
    EXPECT_EQ(q.pnu, c.pnu);
  }
}

TEST(UssPkw, RequestIds) {
  // C 4.2.1.1 Tabelle 4.1.
  EXPECT_EQ(read_request_id(PkwTarget::Value), 1);
  EXPECT_EQ(read_request_id(PkwTarget::Description), 4);
  EXPECT_EQ(read_request_id(PkwTarget::ArrayElement), 6);
  EXPECT_EQ(read_request_id(PkwTarget::Text), 15);
  struct Case {
    PkwTarget target;
    PkwWidth width;
    bool eeprom;
    std::optional<std::uint8_t> id;
  };
  for (const Case& c : {
           Case{PkwTarget::Value, PkwWidth::Word, false, 2},
           Case{PkwTarget::Value, PkwWidth::Dword, false, 3},
           Case{PkwTarget::Value, PkwWidth::Word, true, 14},
           Case{PkwTarget::Value, PkwWidth::Dword, true, 13},
           Case{PkwTarget::ArrayElement, PkwWidth::Word, false, 7},
           Case{PkwTarget::ArrayElement, PkwWidth::Dword, false, 8},
           Case{PkwTarget::ArrayElement, PkwWidth::Word, true, 12},
           Case{PkwTarget::ArrayElement, PkwWidth::Dword, true, 11},
           Case{PkwTarget::Description, PkwWidth::Word, false, 5},
           Case{PkwTarget::Description, PkwWidth::Word, true, std::nullopt},
           Case{PkwTarget::Text, PkwWidth::Word, false, 15},
           Case{PkwTarget::Text, PkwWidth::Word, true, std::nullopt},
       }) {
    EXPECT_EQ(write_request_id(c.target, c.width, c.eeprom), c.id)
        << int(c.target) << " " << int(c.width) << " " << c.eeprom;
  }
}

TEST(UssPkw, PositiveRepliesOfTabelle43) {
  const std::array<std::set<std::uint8_t>, 16> expected{{
      {0},
      {1, 2},
      {1},
      {2},
      {3},
      {3},
      {4, 5},
      {4},
      {5},
      {6},
      {},
      {5},
      {4},
      {2},
      {1},
      {15},
  }};
  for (std::uint8_t req = 0; req < 16; ++req) {
    std::set<std::uint8_t> got;
    for (std::uint8_t id : positive_reply_ids(req)) {
      if (id != 0xFF) got.insert(id);
    }
    EXPECT_EQ(got, expected[req]) << int(req);
    // Every reply id against every request: Matches exactly for the table's ids.
    for (std::uint8_t rep = 0; rep < 16; ++rep) {
      const ReplyClass cls = classify_reply(make(req, 52, 3), make(rep, 52, 3));
      if (rep >= 9 && rep <= 12) {
        EXPECT_EQ(cls, ReplyClass::Spontaneous);
      } else if (expected[req].count(rep) != 0) {
        EXPECT_EQ(cls, ReplyClass::Matches) << int(req) << "/" << int(rep);
      } else if (rep == 7 && req != 0) {
        EXPECT_EQ(cls, ReplyClass::Error) << int(req);
      } else if (rep == 8 && req != 0 && is_change_request(make(req, 52, 3))) {
        EXPECT_EQ(cls, ReplyClass::NoAuthority) << int(req);
      } else {
        EXPECT_EQ(cls, ReplyClass::Unrelated) << int(req) << "/" << int(rep);
      }
    }
  }
}

TEST(UssPkw, ChangeRequestsAndIndexUse) {
  // Footnote 1 of Tabelle 4.1: IND belongs to the request for 4..8, 11, 12, 15.
  const std::set<std::uint8_t> uses_ind{4, 5, 6, 7, 8, 11, 12, 15};
  const std::set<std::uint8_t> changes{2, 3, 5, 7, 8, 11, 12, 13, 14};
  for (std::uint8_t id = 0; id < 16; ++id) {
    EXPECT_EQ(request_uses_ind(id), uses_ind.count(id) == 1) << int(id);
    if (id != 15) {
      EXPECT_EQ(is_change_request(make(id, 1)), changes.count(id) == 1) << int(id);
    }
  }
  EXPECT_FALSE(is_change_request(make(15, 7, make_text_ind(3, false))));
  EXPECT_TRUE(is_change_request(make(15, 7, make_text_ind(3, true))));
}

TEST(UssPkw, StaleRepliesAreUnrelated) {
  // C 4.2.1.1: the slave goes on answering the old request until it has seen the new one.
  const Pkw read_p52 = make(1, 52);
  EXPECT_EQ(classify_reply(read_p52, make(1, 52)), ReplyClass::Matches);
  EXPECT_EQ(classify_reply(read_p52, make(2, 52)), ReplyClass::Matches);       // dword value
  EXPECT_EQ(classify_reply(read_p52, make(1, 53)), ReplyClass::Unrelated);     // other PNU
  EXPECT_EQ(classify_reply(read_p52, make(4, 52, 3)), ReplyClass::Unrelated);  // array reply
  EXPECT_EQ(classify_reply(read_p52, make(0, 0)), ReplyClass::Unrelated);      // "no reply" yet
  EXPECT_EQ(classify_reply(read_p52, make(7, 53)), ReplyClass::Unrelated);     // error, other PNU
  EXPECT_EQ(classify_reply(read_p52, make(7, 52)), ReplyClass::Error);
  // Reads are always processed: "no authority" belongs to an older change request.
  EXPECT_EQ(classify_reply(read_p52, make(8, 52)), ReplyClass::Unrelated);

  const Pkw read_elem3 = make(6, 4, 3);
  EXPECT_EQ(classify_reply(read_elem3, make(4, 4, 3)), ReplyClass::Matches);
  EXPECT_EQ(classify_reply(read_elem3, make(5, 4, 3)), ReplyClass::Matches);
  EXPECT_EQ(classify_reply(read_elem3, make(4, 4, 2)), ReplyClass::Unrelated);  // other element
  EXPECT_EQ(classify_reply(read_elem3, make(7, 4, 2)), ReplyClass::Unrelated);
  EXPECT_EQ(classify_reply(read_elem3, make(7, 4, 3)), ReplyClass::Error);
  // Device-specific IND bits 10..15 are not compared.
  EXPECT_EQ(classify_reply(read_elem3, make(4, 4, 0xFC03)), ReplyClass::Matches);

  const Pkw write_word = make(2, 18);
  EXPECT_EQ(classify_reply(write_word, make(1, 18)), ReplyClass::Matches);
  EXPECT_EQ(classify_reply(write_word, make(2, 18)), ReplyClass::Unrelated);  // reply to dword
  EXPECT_EQ(classify_reply(write_word, make(8, 18)), ReplyClass::NoAuthority);
  EXPECT_EQ(classify_reply(write_word, make(8, 19)), ReplyClass::Unrelated);
  // Non-indexed requests do not look at IND.
  EXPECT_EQ(classify_reply(write_word, make(1, 18, 5)), ReplyClass::Matches);

  // Text: bits 8/9 of IND must be those of the request (Tab. 4.9 "je nach gestelltem Auftrag").
  const Pkw read_text = make(15, 7, make_text_ind(3, false));
  EXPECT_EQ(classify_reply(read_text, make(15, 7, 0x0003)), ReplyClass::Matches);
  EXPECT_EQ(classify_reply(read_text, make(15, 7, 0x0103)), ReplyClass::Unrelated);
  EXPECT_EQ(classify_reply(read_text, make(15, 7, 0x0203)), ReplyClass::Unrelated);
  EXPECT_EQ(classify_reply(read_text, make(15, 7, 0x0004)), ReplyClass::Unrelated);

  // "Kein Auftrag" is answered by "Keine Antwort", any PNU.
  EXPECT_EQ(classify_reply(make(0, 0), make(0, 99)), ReplyClass::Matches);
  EXPECT_EQ(classify_reply(make(0, 0), make(1, 0)), ReplyClass::Unrelated);
  EXPECT_EQ(classify_reply(make(0, 0), make(7, 0)), ReplyClass::Unrelated);
}

TEST(UssPkw, SpontaneousReports) {
  // C 4.2.1.2: ids 9..12 interrupt whatever request is outstanding; the toggle bit marks a new
  // report, the master acknowledges by sending the toggle back changed.
  for (std::uint8_t id = 0; id < 16; ++id) EXPECT_EQ(is_spontaneous(id), id >= 9 && id <= 12);
  const Pkw request = make(1, 52);
  Pkw report = make(9, 300, 0, true);
  report.pwe[0] = 0x1234;
  report.pwe_count = 1;
  EXPECT_EQ(classify_reply(request, report), ReplyClass::Spontaneous);
  EXPECT_EQ(classify_reply(make(0, 0), make(12, 4, 255)), ReplyClass::Spontaneous);
  // The request carries the toggle bit in PKE bit 11 when acknowledging.
  Pkw ack = request;
  ack.toggle = true;
  EXPECT_EQ(ack.pke(), 0x1834);
  EXPECT_EQ(classify_reply(ack, make(1, 52)), ReplyClass::Matches);
}

TEST(UssPkw, Ind) {
  // C 4.2.2.
  EXPECT_EQ(make_ind(PkwTarget::Value, 9), 0);
  EXPECT_EQ(make_ind(PkwTarget::ArrayElement, 2), 2);
  EXPECT_EQ(make_ind(PkwTarget::ArrayElement, kIndWhole), 255);
  EXPECT_EQ(make_ind(PkwTarget::Description, 7), 7);
  EXPECT_EQ(make_ind(PkwTarget::Text, 3), 3);
  // Tab. 4.5 / 4.6: bits 9 8 = 00 read, 01 write, 10 read value texts, 11 write value texts.
  EXPECT_EQ(make_text_ind(3, false, false), 0x0003);
  EXPECT_EQ(make_text_ind(3, true, false), 0x0103);
  EXPECT_EQ(make_text_ind(3, false, true), 0x0203);
  EXPECT_EQ(make_text_ind(254, true, true), 0x03FE);
  EXPECT_EQ(ind_element(0x03FE), 254);
}

TEST(UssPkw, Names) {
  EXPECT_EQ(request_name(1), "read value");
  EXPECT_EQ(request_name(10), "reserved");
  EXPECT_EQ(request_name(16), "invalid");
  EXPECT_EQ(reply_name(7), "request cannot be executed");
  EXPECT_EQ(reply_name(8), "no parameter change authority");
  EXPECT_EQ(reply_name(13), "reserved");
  for (std::uint8_t id = 0; id < 16; ++id) {
    EXPECT_FALSE(request_name(id).empty());
    EXPECT_FALSE(reply_name(id).empty());
  }
  EXPECT_EQ(error_text(0), "parameter number does not exist");
  EXPECT_EQ(error_text(2), "value outside the lower or upper limit");
  EXPECT_EQ(error_text(7), "description element cannot be changed");
  EXPECT_EQ(error_text(50), "error defined by the drive profile");
  EXPECT_EQ(error_text(100), "reserved");
  EXPECT_EQ(error_text(101), "device-specific error");
  EXPECT_EQ(to_string(ReplyClass::NoAuthority), "no authority");
}

TEST(UssPwe, Placement) {
  // C 4.2.3 note: PKW_ANZ = 4: words in PWE2 with PWE1 = 0; PKW_ANZ = 127: words in PWE1;
  // double words PWE1 high, PWE2 low.
  struct Case {
    PkwLength len;
    PkwWidth width;
    std::uint32_t v;
    std::vector<std::uint16_t> pwe;
  };
  for (const Case& c : {
           Case{PkwLength::Three, PkwWidth::Word, 0x4000, {0x4000}},
           Case{PkwLength::Four, PkwWidth::Word, 0x7000, {0x0000, 0x7000}},
           Case{PkwLength::Four, PkwWidth::Dword, 0x40000000, {0x4000, 0x0000}},
           Case{PkwLength::Variable, PkwWidth::Word, 0x1234, {0x1234}},
           Case{PkwLength::Variable, PkwWidth::Dword, 0x12345678, {0x1234, 0x5678}},
           Case{PkwLength::None, PkwWidth::Word, 0x1234, {}},
       }) {
    Pkw p;
    set_value(p, c.len, c.width, c.v);
    EXPECT_EQ(std::vector<std::uint16_t>(p.pwe_words().begin(), p.pwe_words().end()), c.pwe);
    if (c.len != PkwLength::None) {
      EXPECT_EQ(value(p, c.len, c.width), c.v);
    }
  }
  EXPECT_EQ(reply_width(2), PkwWidth::Dword);
  EXPECT_EQ(reply_width(5), PkwWidth::Dword);
  EXPECT_EQ(reply_width(10), PkwWidth::Dword);
  EXPECT_EQ(reply_width(12), PkwWidth::Dword);
  EXPECT_EQ(reply_width(1), PkwWidth::Word);
  EXPECT_EQ(reply_width(11), PkwWidth::Word);
  Pkw err = make(7, 52);
  set_value(err, PkwLength::Four, PkwWidth::Word, 3);
  EXPECT_EQ(error_number(err, PkwLength::Four), 3);
  set_value(err, PkwLength::Three, PkwWidth::Word, 101);
  EXPECT_EQ(error_number(err, PkwLength::Three), 101);
}

TEST(UssPayload, SizesAndRefusals) {
  Pkw p = make(1, 52);
  EXPECT_EQ(pkw_bytes(PkwLength::None, p), 0U);
  EXPECT_EQ(pkw_bytes(PkwLength::Three, p), 6U);
  EXPECT_EQ(pkw_bytes(PkwLength::Four, p), 8U);
  EXPECT_EQ(pkw_bytes(PkwLength::Variable, p), 6U);  // at least PKE IND PWE1
  p.pwe_count = 8;
  EXPECT_EQ(pkw_bytes(PkwLength::Variable, p), 20U);

  std::array<std::uint8_t, 260> out{};
  const std::array<std::uint16_t, 2> pzd{0x047F, 0x2000};
  // A double word does not fit 3 PKW words (C 7 example).
  Pkw dw = make(3, 52);
  set_value(dw, PkwLength::Three, PkwWidth::Dword, 0x10000);
  EXPECT_EQ(encode_payload(dw, PkwLength::Three, pzd, out), 0U);
  EXPECT_EQ(encode_payload(dw, PkwLength::Four, pzd, out), 12U);
  // PNU beyond 11 bits, AK beyond 4 bits.
  EXPECT_EQ(encode_payload(make(1, 2048), PkwLength::Three, pzd, out), 0U);
  EXPECT_EQ(encode_payload(make(16, 1), PkwLength::Three, pzd, out), 0U);
  // 17 PZD words.
  const std::array<std::uint16_t, 17> pzd17{};
  EXPECT_EQ(encode_payload(make(0, 0), PkwLength::None, pzd17, out), 0U);
  // Variable: 124 PWE words and no PZD = 252 bytes; with one PZD word it is too long.
  Pkw big = make(15, 7);
  big.pwe_count = 124;
  EXPECT_EQ(encode_payload(big, PkwLength::Variable, {}, out), 252U);
  const std::array<std::uint16_t, 1> one{1};
  EXPECT_EQ(encode_payload(big, PkwLength::Variable, one, out), 0U);
  // 108 PWE words with 16 PZD words = 252 bytes (C 4.1.2: m <= 108 with 16 PZD).
  big.pwe_count = 108;
  const std::array<std::uint16_t, 16> pzd16{};
  EXPECT_EQ(encode_payload(big, PkwLength::Variable, pzd16, out), 252U);
  // out too small.
  std::array<std::uint8_t, 9> small{};
  EXPECT_EQ(encode_payload(make(1, 52), PkwLength::Three, pzd, small), 0U);
}

TEST(UssPayload, FixedLge) {
  // A 4.2 LGE = n + 2 with n = PKW bytes + PZD bytes.
  EXPECT_EQ(fixed_lge(PkwLength::Three, 2), 12);  // C 8 examples 2-4
  EXPECT_EQ(fixed_lge(PkwLength::Four, 0), 10);   // C 8 examples 5, 6
  EXPECT_EQ(fixed_lge(PkwLength::None, 2), 6);    // C 8 example 1
  EXPECT_EQ(fixed_lge(PkwLength::Four, 16), 42);
  EXPECT_EQ(fixed_lge(PkwLength::Variable, 2), 0);
}

TEST(UssPayload, RoundTripAndDecodeRefusals) {
  Pkw p = make(11, 4, 2, true);
  set_value(p, PkwLength::Four, PkwWidth::Dword, 0xDEADBEEF);
  const std::array<std::uint16_t, 3> pzd{0x047F, 0x2000, 0x8001};
  std::array<std::uint8_t, 64> out{};
  const std::size_t n = encode_payload(p, PkwLength::Four, pzd, out);
  ASSERT_EQ(n, 14U);
  Pkw q;
  std::array<std::uint16_t, 16> pzd_in{};
  ASSERT_TRUE(decode_payload({out.data(), n}, PkwLength::Four, 3, q, pzd_in));
  EXPECT_EQ(q, p);
  EXPECT_EQ(pzd_in[2], 0x8001);

  std::array<std::uint16_t, 2> two{};
  EXPECT_FALSE(decode_payload({out.data(), n}, PkwLength::Four, 3, q, two));      // pzd_out small
  EXPECT_FALSE(decode_payload({out.data(), n}, PkwLength::Three, 3, q, pzd_in));  // wrong size
  EXPECT_FALSE(decode_payload({out.data(), n - 1}, PkwLength::Four, 3, q, pzd_in));  // odd
  EXPECT_FALSE(decode_payload({out.data(), 2}, PkwLength::Variable, 0, q, pzd_in));  // no IND
  EXPECT_FALSE(decode_payload({out.data(), 4}, PkwLength::None, 1, q, pzd_in));
  EXPECT_TRUE(decode_payload({out.data(), 4}, PkwLength::None, 2, q, pzd_in));
  EXPECT_EQ(q, Pkw{});
  EXPECT_EQ(pzd_in[0], 0xB804);  // PKE of request 11, toggle, PNU 4
}

}  // namespace
}  // namespace liftd::uss
