// BoardCanPort against the real kernel CAN stack in the kernel rig's guest: on vcan, and on two emulated Kvaser
// PCI controllers (SJA1000, Debian's sja1000 and kvaser_pci drivers) on one emulated bus at 1 Mbit/s. Run by
// tests/kernel/board_can.sh, which sets:
//   LEVER_CAN_A, LEVER_CAN_B  the interfaces of the two ports (vcan0 and vcan0, or can0 and can1)
// can-utils and iproute2 are the independent peers (can_peer.hpp). The guest's clock is emulated and slow: the
// tests wait for what must happen, with a generous bound, and assert what was delivered, never how fast.
// Tags: [bus] runs on either kind of interface, [vcan] needs vcan (interfaces made and removed, error frames
// injected, a netem queue), [kvaser] needs the emulated controllers.
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "can_peer.hpp"
#include "lever/board/board_can_port.hpp"
#include "lever/protocol/messages.hpp"

using lever::board::BoardCanPort;
using lever::board::BoardCanPortConfig;
using lever::board::CanBusState;
using lever::board::LinkState;
using lever::protocol::CanFrame;
using lever::protocol::Role;
using lever::test::Background;
using lever::test::Candump;
using lever::test::LoggedFrame;
using lever::test::output_of;
using lever::test::run;

namespace {

constexpr std::uint8_t kPair = 3;
const std::uint32_t kMotion = lever::protocol::motion_id(kPair);
const std::uint32_t kForce = lever::protocol::force_id(kPair);
const std::uint32_t kOwnIds[] = {lever::protocol::command_id(kPair), kMotion, kForce,
                                 lever::protocol::heartbeat_id(kPair, Role::hsi),
                                 lever::protocol::heartbeat_id(kPair, Role::top)};

std::string env(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') FAIL(name << " is not set: run this through tests/kernel/board_can.sh");
  return v;
}

std::string out_dir() {
  const char* v = std::getenv("LEVER_RIG_OUT");
  return v != nullptr && *v != '\0' ? v : "/tmp";
}

BoardCanPort open_port(const std::string& interface) {
  BoardCanPortConfig config;
  config.interface = interface;
  config.pair = kPair;
  config.link_retry_ms = 10;
  config.link_retry_max_ms = 200;
  auto port = BoardCanPort::open(config);
  if (!port) FAIL("BoardCanPort::open(" << interface << "): " << port.error().message);
  return std::move(port).value();
}

// Every call into a port goes through these two, which count the heap allocations made inside it: zero is
// part of every test.
std::uint64_t g_allocations = 0;
bool receive(BoardCanPort& port, CanFrame& frame) {
  lever::test::alloc_count_begin();
  const bool got = port.receive(frame);
  g_allocations += lever::test::alloc_count_end();
  return got;
}
bool send(BoardCanPort& port, const CanFrame& frame) {
  lever::test::alloc_count_begin();
  const bool sent = port.send(frame);
  g_allocations += lever::test::alloc_count_end();
  return sent;
}
void check_no_allocations() {
  CHECK(g_allocations == 0);
  g_allocations = 0;
}

CanFrame make_frame(std::uint32_t id, std::uint32_t seq) {
  CanFrame f;
  f.id = id;
  f.dlc = 8;
  for (int i = 0; i < 4; ++i) f.data[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(seq >> (8 * i));
  // Every byte set, and the last differing from frame to frame: a byte lost anywhere shows.
  f.data[4] = static_cast<std::uint8_t>(id);
  f.data[5] = 0xA5;
  f.data[6] = static_cast<std::uint8_t>(id >> 8 | 0x80);
  f.data[7] = static_cast<std::uint8_t>(0x3C ^ seq);
  return f;
}

bool same(const CanFrame& a, const CanFrame& b) { return a.id == b.id && a.dlc == b.dlc && a.data == b.data; }

std::string hex(const CanFrame& f) {
  std::string s;
  char byte[3];
  for (std::size_t i = 0; i < f.dlc; ++i) {
    std::snprintf(byte, sizeof byte, "%02X", f.data[i]);
    s += byte;
  }
  return s;
}

std::string hex_id(std::uint32_t id) {
  char s[8];
  std::snprintf(s, sizeof s, "%03X", static_cast<unsigned>(id));
  return s;
}

// Waits for `done` with a bound of a minute of the guest's clock, trying every millisecond.
bool eventually(const std::function<bool()>& done) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// The test needs every frame out: a full queue is waited out here (the firmware would drop and count).
void send_surely(BoardCanPort& port, const CanFrame& frame) {
  REQUIRE(eventually([&] { return send(port, frame); }));
}

// Everything the port has now, after waiting for `count` frames (or the bound).
std::vector<CanFrame> receive_count(BoardCanPort& port, std::size_t count) {
  std::vector<CanFrame> got;
  eventually([&] {
    CanFrame f;
    while (receive(port, f)) got.push_back(f);
    return got.size() >= count;
  });
  return got;
}

// Sends `count` frames from one port to the other, receiving as they come (the receiver's queue is finite),
// and checks that exactly these arrived, in order.
void check_crossing(BoardCanPort& from, BoardCanPort& to, std::uint32_t id, std::uint32_t count,
                    std::uint32_t first_seq = 0) {
  std::vector<CanFrame> got;
  for (std::uint32_t i = 0; i < count; ++i) {
    send_surely(from, make_frame(id, first_seq + i));
    CanFrame f;
    while (receive(to, f)) got.push_back(f);
  }
  for (auto& f : receive_count(to, count - got.size())) got.push_back(f);
  REQUIRE(got.size() == count);
  std::uint32_t mismatches = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    if (!same(got[i], make_frame(id, first_seq + i))) ++mismatches;
  }
  CHECK(mismatches == 0);
}

// The state line of `ip -details link show`: "ERROR-ACTIVE", ... (empty for vcan, which has none).
std::string kernel_state(const std::string& interface) {
  const std::string text = output_of({"ip", "-details", "link", "show", interface});
  const auto at = text.find(" state ERROR-");
  const auto off = text.find(" state BUS-OFF");
  if (off != std::string::npos) return "BUS-OFF";
  if (at == std::string::npos) return "";
  const auto end = text.find(' ', at + 7);
  return text.substr(at + 7, end - (at + 7));
}

std::string upper_name(CanBusState s) {
  std::string n(lever::board::name(s));
  for (auto& c : n) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return n;
}

}  // namespace

TEST_CASE("frames cross between two ports, both ways, exactly", "[bus]") {
  auto a = open_port(env("LEVER_CAN_A"));
  auto b = open_port(env("LEVER_CAN_B"));
  REQUIRE(a.link() == LinkState::up);
  constexpr std::uint32_t n = 300;
  check_crossing(a, b, kMotion, n);
  check_crossing(b, a, kForce, n);
  const auto sa = a.stats(), sb = b.stats();
  std::printf("board-can: %u frames %s -> %s and %u back; queue-full drops while sending: %llu and %llu\n", n,
              std::string(a.interface()).c_str(), std::string(b.interface()).c_str(), n,
              static_cast<unsigned long long>(sa.tx_dropped), static_cast<unsigned long long>(sb.tx_dropped));
  CHECK(sa.tx_frames == n);
  CHECK(sb.rx_frames == n);
  CHECK(sb.tx_frames == n);
  CHECK(sa.rx_frames == n);
  CHECK(sa.rx_skipped == 0);
  CHECK(sa.rx_kernel_drops == 0);
  CHECK(sb.rx_kernel_drops == 0);
  CHECK(a.bus_counts().error_frames == 0);
  CHECK(a.bus_state() == CanBusState::error_active);
  check_no_allocations();
}

TEST_CASE("candump sees what a port sends, and cansend's frames reach a port", "[bus]") {
  const std::string if_a = env("LEVER_CAN_A"), if_b = env("LEVER_CAN_B");
  auto a = open_port(if_a);
  // candump on the other interface: on the Kvaser controllers the frames must cross the emulated bus.
  Candump dump(if_b, out_dir() + "/candump-seen.log");
  std::vector<CanFrame> sent;
  for (std::uint32_t k = 0; k < 4; ++k) {
    for (const auto id : kOwnIds) {
      sent.push_back(make_frame(id, k));
      send_surely(a, sent.back());
    }
  }
  REQUIRE(eventually([&] {
    std::size_t own = 0;
    for (const auto& f : lever::test::read_candump_log(out_dir() + "/candump-seen.log")) own += f.id != "7FF";
    return own >= sent.size();
  }));
  const auto logged = dump.stop();
  REQUIRE(logged.size() == sent.size());
  for (std::size_t i = 0; i < sent.size(); ++i) {
    CHECK(logged[i].interface == if_b);
    CHECK(logged[i].id == hex_id(sent[i].id));
    CHECK(logged[i].data == hex(sent[i]));
  }

  // cansend on the other side, every id of the pair: each arrives, byte for byte.
  std::uint32_t seq = 100;
  for (const auto id : kOwnIds) {
    const CanFrame expected = make_frame(id, seq++);
    REQUIRE(run({"cansend", if_b, hex_id(id) + "#" + hex(expected)}) == 0);
    const auto got = receive_count(a, 1);
    REQUIRE(got.size() == 1);
    CHECK(same(got[0], expected));
  }
  std::printf("board-can: candump on %s logged the %zu frames sent on %s; 5 cansend frames reached the port\n",
              if_b.c_str(), sent.size(), if_a.c_str());
  CHECK(a.stats().rx_frames == 5);
  check_no_allocations();
}

TEST_CASE("the kernel keeps a flood of foreign frames away from the port", "[bus]") {
  const std::string if_a = env("LEVER_CAN_A"), if_b = env("LEVER_CAN_B");
  auto a = open_port(if_a);
  auto b = open_port(if_b);
  Candump dump(if_a, out_dir() + "/candump-flood.log");
  // Another pair's frames (0x084, 0x104, 0x114, pair 4's heartbeat), an id outside the protocol, and the
  // port's own motion id as an extended and as a remote frame. -p: wait out a full queue, so the counts hold.
  // The remote frames have DLC 0 (and so no -D i, which makes the DLC at least 1): QEMU's SJA1000 stores a
  // remote frame's DLC worth of data bytes in its receive FIFO but releases only the 3 header bytes, so one
  // with a DLC above 0 corrupts the receiving controller's FIFO for good (seen: garbage ids, then frames lost).
  const std::string cangen = "cangen " + if_b + " -g 0 -p 100";
  const std::vector<std::pair<std::string, int>> floods = {
      {"-L 8 -D i -I 104", 1500}, {"-L 8 -D i -I 084", 500},    {"-L 8 -D i -I 114", 500},   {"-L 8 -D i -I 708", 500},
      {"-L 8 -D i -I 6FF", 500},  {"-L 8 -D i -e -I 103", 500}, {"-L 0 -D r -R -I 103", 500}};
  std::string script = "set -e";
  int foreign = 0;
  for (const auto& [args, count] : floods) {
    script += "; " + cangen + " " + args + " -n " + std::to_string(count);
    foreign += count;
  }
  Background flood({"sh", "-c", script});
  // The port's own frames from the other port while the flood runs; the port under test reads nothing yet,
  // so anything the kernel let through would pile up in its receive queue and overflow it.
  constexpr std::uint32_t own = 100;
  for (std::uint32_t i = 0; i < own; ++i) send_surely(b, make_frame(kMotion, i));
  REQUIRE(flood.wait() == 0);
  REQUIRE(eventually([&] {
    return lever::test::read_candump_log(out_dir() + "/candump-flood.log").size() >=
           static_cast<std::size_t>(foreign) + own;
  }));
  const auto logged = dump.stop();

  const auto got = receive_count(a, own);
  CanFrame extra;
  const bool more = receive(a, extra);
  REQUIRE(got.size() == own);
  CHECK_FALSE(more);
  std::uint32_t mismatches = 0;
  for (std::uint32_t i = 0; i < own; ++i) mismatches += same(got[i], make_frame(kMotion, i)) ? 0 : 1;
  CHECK(mismatches == 0);
  const auto s = a.stats();
  std::printf(
      "board-can: flood on %s: candump logged %zu frames (%d foreign, %u own); the port received %llu, "
      "skipped %llu, kernel drops %llu\n",
      if_b.c_str(), logged.size(), foreign, own, static_cast<unsigned long long>(s.rx_frames),
      static_cast<unsigned long long>(s.rx_skipped), static_cast<unsigned long long>(s.rx_kernel_drops));
  CHECK(logged.size() == static_cast<std::size_t>(foreign) + own);
  CHECK(s.rx_frames == own);
  CHECK(s.rx_skipped == 0);  // not even an extended or remote frame reached the socket
  CHECK(s.rx_kernel_drops == 0);
  check_no_allocations();
}

TEST_CASE("frames the kernel drops for a full receive queue are counted, never silent", "[bus]") {
  const std::string if_a = env("LEVER_CAN_A"), if_b = env("LEVER_CAN_B");
  auto a = open_port(if_a);
  auto b = open_port(if_b);
  // The port reads nothing while far more frames come than its receive queue holds.
  constexpr std::uint32_t burst = 2000;
  for (std::uint32_t i = 0; i < burst; ++i) send_surely(b, make_frame(kMotion, i));
  // Read what the queue kept, until nothing has come for a while (on the Kvaser controllers the last frames
  // may still be on their way; any that come later are read below all the same).
  std::vector<CanFrame> got;
  for (int quiet = 0; quiet < 200;) {
    CanFrame f;
    if (receive(a, f)) {
      got.push_back(f);
      quiet = 0;
    } else {
      ++quiet;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  const std::size_t kept = got.size();
  // The kernel hands its drop count over with the next frame it queues (SO_RXQ_OVFL): one more, now that
  // there is room, and everything up to it.
  const CanFrame last = make_frame(kMotion, burst);
  send_surely(b, last);
  REQUIRE(eventually([&] {
    CanFrame f;
    while (receive(a, f)) got.push_back(f);
    return !got.empty() && same(got.back(), last);
  }));
  const auto s = a.stats();
  std::printf("board-can: %u frames at a port that did not read: %zu kept, %llu counted as kernel drops\n", burst, kept,
              static_cast<unsigned long long>(s.rx_kernel_drops));
  CHECK(s.rx_kernel_drops > 0);
  CHECK(s.rx_frames == got.size());
  CHECK(s.rx_frames + s.rx_kernel_drops == burst + 1);
  // What came is a part of the burst in its order: the queue dropped frames, never reordered or altered them.
  std::uint32_t out_of_order = 0, next = 0;
  for (const auto& f : got) {
    const std::uint32_t seq = f.data[0] | (f.data[1] << 8) | (f.data[2] << 16) | (std::uint32_t{f.data[3]} << 24);
    if (seq < next || !same(f, make_frame(kMotion, seq))) ++out_of_order;
    next = seq + 1;
  }
  CHECK(out_of_order == 0);
  check_no_allocations();
}

TEST_CASE("the interface goes down and comes up: the port reports it and recovers", "[bus]") {
  const std::string if_a = env("LEVER_CAN_A"), if_b = env("LEVER_CAN_B");
  auto a = open_port(if_a);
  auto b = open_port(if_b);
  check_crossing(a, b, kMotion, 5);

  REQUIRE(run({"ip", "link", "set", if_a, "down"}) == 0);
  CHECK_FALSE(send(a, make_frame(kMotion, 1000)));
  CHECK(a.link() == LinkState::down);
  CHECK(a.stats().tx_link_down == 1);
  CHECK(a.stats().link_losses == 1);
  CanFrame f;
  CHECK_FALSE(receive(a, f));
  CHECK(a.link() == LinkState::down);  // still down: receive() looked again and found it so

  REQUIRE(run({"ip", "link", "set", if_a, "up"}) == 0);
  // receive() alone brings the port back (it looks at the link when its retry time is due); on vcan both ports
  // share the interface and both went down.
  REQUIRE(eventually([&] {
    receive(a, f);
    receive(b, f);
    return a.link() == LinkState::up && b.link() == LinkState::up;
  }));
  check_crossing(a, b, kMotion, 20, 10);
  check_crossing(b, a, kForce, 20, 10);
  const auto s = a.stats();
  std::printf("board-can: %s down and up: link losses %llu, reopens %llu, frames crossed both ways after\n",
              if_a.c_str(), static_cast<unsigned long long>(s.link_losses), static_cast<unsigned long long>(s.reopens));
  CHECK(s.link_losses == 1);
  CHECK(s.reopens == 0);  // the socket stayed bound through down and up
  CHECK(a.bus_state() == CanBusState::error_active);
  check_no_allocations();
}

TEST_CASE("an interface removed and made again: the port reopens its socket", "[vcan]") {
  // vcan1, so that the other tests' vcan0 stays as the rig made it.
  auto a = open_port("vcan1");
  auto b = open_port("vcan1");
  check_crossing(a, b, kMotion, 5);

  REQUIRE(run({"ip", "link", "del", "vcan1"}) == 0);
  CanFrame f;
  CHECK_FALSE(receive(a, f));
  CHECK(a.link() == LinkState::gone);
  CHECK_FALSE(send(a, make_frame(kMotion, 1000)));
  CHECK(a.stats().tx_link_down == 1);
  // Looking again while it is gone changes nothing.
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  CHECK_FALSE(receive(a, f));
  CHECK(a.link() == LinkState::gone);

  REQUIRE(run({"ip", "link", "add", "dev", "vcan1", "type", "vcan"}) == 0);
  REQUIRE(run({"ip", "link", "set", "vcan1", "up"}) == 0);
  REQUIRE(eventually([&] {
    receive(a, f);
    receive(b, f);
    return a.link() == LinkState::up && b.link() == LinkState::up;
  }));
  check_crossing(a, b, kMotion, 20, 10);
  check_crossing(b, a, kForce, 20, 10);
  std::printf("board-can: vcan1 removed and made again: reopens %llu, frames crossed both ways after\n",
              static_cast<unsigned long long>(a.stats().reopens));
  CHECK(a.stats().reopens == 1);
  CHECK(a.stats().link_losses == 1);
  check_no_allocations();  // the reopen happened inside receive()
}

TEST_CASE("error frames are consumed by the port and mapped to the bus state", "[vcan]") {
  // vcan has no controller, but a frame with CAN_ERR_FLAG sent on it reaches every socket on it as an error
  // frame, through the same CAN_RAW_ERR_FILTER a driver's error frames pass: cansend plays the driver.
  const std::string interface = env("LEVER_CAN_A");
  auto a = open_port(interface);
  std::uint32_t seq = 0;
  // One error frame, then a data frame of the pair: the port must hand over the data frame only.
  auto inject = [&](const std::string& error_frame) {
    REQUIRE(run({"cansend", interface, error_frame}) == 0);
    const CanFrame marker = make_frame(kMotion, seq++);
    REQUIRE(run({"cansend", interface, hex_id(kMotion) + "#" + hex(marker)}) == 0);
    const auto got = receive_count(a, 1);
    REQUIRE(got.size() == 1);
    CHECK(same(got[0], marker));
  };
  const auto& c = a.bus_counts();
  CHECK(a.bus_state() == CanBusState::error_active);
  inject("20000004#0008000000000000");  // controller: TX warning
  CHECK(a.bus_state() == CanBusState::error_warning);
  inject("20000004#0020000000000000");  // controller: TX passive
  CHECK(a.bus_state() == CanBusState::error_passive);
  inject("20000040#0000000000000000");  // bus-off
  CHECK(a.bus_state() == CanBusState::bus_off);
  CHECK(c.bus_off_count == 1);
  inject("20000100#0000000000000000");  // restarted
  CHECK(a.bus_state() == CanBusState::error_active);
  CHECK(c.restarts == 1);
  inject("20000228#0000190000002A00");  // no ACK + protocol error, with the error counters
  CHECK(c.ack_errors == 1);
  CHECK(c.bus_errors == 1);
  CHECK(c.tx_error_counter == 0x2A);
  inject("20000004#0004000000000000");  // controller: RX warning
  CHECK(a.bus_state() == CanBusState::error_warning);
  inject("20000004#0040000000000000");  // controller: back to error-active
  CHECK(a.bus_state() == CanBusState::error_active);
  inject("20000004#0001000000000000");  // controller: RX overflow, no state change
  CHECK(c.rx_overflows == 1);
  CHECK(a.bus_state() == CanBusState::error_active);
  inject("20000002#0000000000000000");  // arbitration lost: not asked for, never delivered
  std::printf("board-can: %llu injected error frames consumed; the port handed over only the %u data frames\n",
              static_cast<unsigned long long>(c.error_frames), seq);
  CHECK(c.error_frames == 8);
  CHECK(c.warnings == 2);
  CHECK(c.passives == 1);
  CHECK(a.stats().rx_frames == seq);
  check_no_allocations();
}

TEST_CASE("an error flood holds one receive() call for a bounded number of reads", "[vcan]") {
  const std::string interface = env("LEVER_CAN_A");
  auto a = open_port(interface);
  constexpr std::size_t flood = 2 * BoardCanPort::kMaxReadsPerReceive + 8;
  const CanFrame marker = make_frame(kMotion, 7);
  // Bus errors, as a controller with berr-reporting on sends them for every bad frame; then one data frame.
  REQUIRE(run({"sh", "-c",
               "for i in $(seq " + std::to_string(flood) + "); do cansend " + interface +
                   " 20000088#0000190000000000 || exit 1; done; cansend " + interface + " " + hex_id(kMotion) + "#" +
                   hex(marker)}) == 0);
  CanFrame f;
  CHECK_FALSE(receive(a, f));
  CHECK(a.bus_counts().error_frames == BoardCanPort::kMaxReadsPerReceive);
  CHECK_FALSE(receive(a, f));
  CHECK(a.bus_counts().error_frames == 2 * BoardCanPort::kMaxReadsPerReceive);
  REQUIRE(receive(a, f));  // the rest of the flood, then the frame
  CHECK(same(f, marker));
  CHECK(a.bus_counts().error_frames == flood);
  CHECK(a.bus_counts().bus_errors == flood);
  check_no_allocations();
}

TEST_CASE("a controller brought down and up again is error-active, whatever it was before", "[vcan]") {
  const std::string interface = env("LEVER_CAN_A");
  auto a = open_port(interface);
  auto b = open_port(interface);
  REQUIRE(run({"cansend", interface, "20000040#0000000000000000"}) == 0);  // bus-off
  CHECK(eventually([&] {
    CanFrame f;
    receive(a, f);
    return a.bus_state() == CanBusState::bus_off;
  }));
  REQUIRE(run({"ip", "link", "set", interface, "down"}) == 0);
  REQUIRE(run({"ip", "link", "set", interface, "up"}) == 0);
  // The socket's pending ENETDOWN tells the port the interface went down; it then finds it up again.
  CanFrame f;
  REQUIRE(eventually([&] {
    receive(a, f);
    receive(b, f);
    return a.stats().link_losses == 1 && a.link() == LinkState::up && b.link() == LinkState::up;
  }));
  CHECK(a.bus_state() == CanBusState::error_active);
  CHECK(a.bus_counts().restarts == 0);
  check_crossing(b, a, kForce, 5);
  check_no_allocations();
}

TEST_CASE("a full transmit queue: frames are dropped and counted, the port never waits", "[vcan]") {
  // netem holds what is sent for a minute and queues at most 5: the sixth frame gets ENOBUFS, as on a board
  // whose controller cannot get frames out (bus-off, or a bus too busy).
  const std::string interface = env("LEVER_CAN_A");
  auto a = open_port(interface);
  auto b = open_port(interface);
  REQUIRE(run({"tc", "qdisc", "add", "dev", interface, "root", "netem", "delay", "60s", "limit", "5"}) == 0);
  std::vector<std::uint32_t> accepted;
  constexpr std::uint32_t attempts = 50;
  for (std::uint32_t i = 0; i < attempts; ++i) {
    if (send(a, make_frame(kMotion, i))) accepted.push_back(i);
  }
  // The frames the queue took reach the other socket at once, by the CAN core's local loopback.
  const auto got = receive_count(b, accepted.size());
  REQUIRE(run({"tc", "qdisc", "del", "dev", interface, "root"}) == 0);
  const auto s = a.stats();
  std::printf("board-can: %u sends into a netem queue of 5: %llu taken, %llu dropped as queue full\n", attempts,
              static_cast<unsigned long long>(s.tx_frames), static_cast<unsigned long long>(s.tx_dropped));
  CHECK(s.tx_dropped > 0);
  CHECK(s.tx_frames == accepted.size());
  CHECK(s.tx_frames + s.tx_dropped == attempts);
  CHECK(s.tx_link_down == 0);
  CHECK(s.tx_errors == 0);
  CHECK(a.link() == LinkState::up);  // a full queue is not a lost link
  REQUIRE(got.size() == accepted.size());
  for (std::size_t i = 0; i < got.size(); ++i) CHECK(same(got[i], make_frame(kMotion, accepted[i])));
  check_no_allocations();
}

TEST_CASE("the Kvaser controllers: 1 Mbit/s bit timing, and the port's bus state is the kernel's", "[kvaser]") {
  const std::string if_a = env("LEVER_CAN_A"), if_b = env("LEVER_CAN_B");
  const std::string details = output_of({"ip", "-details", "link", "show", if_a});
  std::printf("board-can: ip -details link show %s:\n%s", if_a.c_str(), details.c_str());
  CHECK(details.find("bitrate 1000000") != std::string::npos);
  CHECK(details.find("sample-point") != std::string::npos);
  CHECK(details.find("sja1000:") != std::string::npos);  // the driver's own timing limits: a real controller
  auto a = open_port(if_a);
  auto b = open_port(if_b);
  CHECK(upper_name(a.bus_state()) == kernel_state(if_a));

  // The other controller goes away: a real bus would leave can0's frames unacknowledged (error-passive after
  // 16 frames). Whatever the emulation does, the port must not block, and must say what the kernel says.
  REQUIRE(run({"ip", "link", "set", if_b, "down"}) == 0);
  std::uint32_t taken = 0;
  for (std::uint32_t i = 0; i < 40; ++i) {
    if (eventually([&] { return send(a, make_frame(kMotion, i)); })) ++taken;
  }
  CanFrame f;
  for (int i = 0; i < 100; ++i) {  // error frames, if any, come in after the sends
    receive(a, f);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const std::string state_alone = kernel_state(if_a);
  std::printf(
      "board-can: %s sent %u frames with %s down: port says %s, kernel says %s, error frames %llu, "
      "ack errors %llu\n",
      if_a.c_str(), taken, if_b.c_str(), std::string(lever::board::name(a.bus_state())).c_str(), state_alone.c_str(),
      static_cast<unsigned long long>(a.bus_counts().error_frames),
      static_cast<unsigned long long>(a.bus_counts().ack_errors));
  CHECK(taken == 40);
  CHECK(upper_name(a.bus_state()) == state_alone);
  // restart is for a controller in bus-off; the kernel refuses it otherwise.
  const int restart = run({"ip", "link", "set", if_a, "type", "can", "restart"});
  std::printf("board-can: ip link set %s type can restart: exit %d (kernel state %s)\n", if_a.c_str(), restart,
              state_alone.c_str());
  if (state_alone != "BUS-OFF") CHECK(restart != 0);
  REQUIRE(run({"ip", "link", "set", if_b, "up"}) == 0);

  // Automatic restart after bus-off, as a board would run: set while the interface is down.
  REQUIRE(run({"ip", "link", "set", if_a, "down"}) == 0);
  REQUIRE(run({"ip", "link", "set", if_a, "type", "can", "restart-ms", "100"}) == 0);
  REQUIRE(run({"ip", "link", "set", if_a, "up"}) == 0);
  CHECK(output_of({"ip", "-details", "link", "show", if_a}).find("restart-ms 100") != std::string::npos);
  REQUIRE(eventually([&] {
    receive(a, f);
    return a.link() == LinkState::up;
  }));
  CHECK(upper_name(a.bus_state()) == kernel_state(if_a));
  check_crossing(a, b, kMotion, 20, 1000);
  check_crossing(b, a, kForce, 20, 1000);
  std::printf("board-can: %s with restart-ms 100 after down/up: port %s, kernel %s; frames crossed both ways\n",
              if_a.c_str(), std::string(lever::board::name(a.bus_state())).c_str(), kernel_state(if_a).c_str());
  check_no_allocations();
}
