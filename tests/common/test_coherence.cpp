// Sender and receiver models are separate objects; they must agree bit for bit while no frame is lost,
// with and without fixed-point quantization on the wire.
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>

#include "lever/codec/codec.hpp"
#include "lever/common/rng.hpp"

using lever::Rng;
using lever::Vec;
using namespace lever::codec;

namespace {

template <typename T, std::size_t N>
bool bit_identical(const Vec<T, N>& a, const Vec<T, N>& b) {
  return std::memcmp(a.data(), b.data(), sizeof(T) * N) == 0;
}

// A noisy, drifting signal with the occasional jump: the worst case for coherence.
template <typename T, std::size_t N>
struct NoisySignal {
  Rng rng;
  Vec<T, N> x{};
  Vec<T, N> next() {
    for (auto& c : x) {
      c += static_cast<T>(0.01 * rng.normal());
      if (rng.uniform() < 0.002) c = static_cast<T>(rng.uniform(-2, 2));
    }
    return x;
  }
};

// Runs a link and returns how many samples were sent; fails the test at the first sample where the
// receiver's reconstruction differs in any bit from what the sender believes it shows.
template <typename T, std::size_t N, typename Q>
int run_link(const Config<T>& config, Q quantizer, std::uint64_t seed) {
  DeadbandSender<T, N, Q> sender(config, quantizer);
  DeadbandReceiver<T, N, Q> receiver(config.mode, quantizer);
  NoisySignal<T, N> signal{Rng(seed)};
  int sent = 0;
  for (int k = 0; k < 5000; ++k) {
    const T t = static_cast<T>(k) * T(1e-3);
    const auto d = sender.offer(t, signal.next());
    if (d.send) {
      receiver.receive(t, d.wire);
      ++sent;
    }
    const auto shown = receiver.reconstruct(t);
    REQUIRE(shown.has_value());
    REQUIRE(bit_identical(*shown, d.value));
    REQUIRE(bit_identical(receiver.model().at(t + T(5e-4)), sender.model().at(t + T(5e-4))));
  }
  return sent;
}

}  // namespace

TEMPLATE_TEST_CASE("sender and receiver stay bit-identical without quantization", "[codec][coherence]", float, double) {
  const auto mode = GENERATE(Mode::deadband, Mode::predictive);
  const auto filter_hz = GENERATE(0.0, 30.0);
  const Config<TestType> config{mode, TestType(0.1), TestType(0.01), static_cast<TestType>(filter_hz)};
  CHECK(run_link<TestType, 1>(config, IdentityQuantizer<TestType>{}, 1) > 10);
  CHECK(run_link<TestType, 3>(config, IdentityQuantizer<TestType>{}, 2) > 10);
}

TEMPLATE_TEST_CASE("sender and receiver stay bit-identical with fixed-point quantization", "[codec][coherence]", float,
                   double) {
  const auto mode = GENERATE(Mode::deadband, Mode::predictive);
  const auto filter_hz = GENERATE(0.0, 30.0);
  const Config<TestType> config{mode, TestType(0.05), TestType(0.0), static_cast<TestType>(filter_hz)};
  const FixedPointQuantizer<TestType, std::int16_t> wire{TestType(1e-3)};  // 1 mN steps, +-32.767 N
  CHECK(run_link<TestType, 1>(config, wire, 3) > 10);
  CHECK(run_link<TestType, 3>(config, wire, 4) > 10);
}

TEST_CASE("a sender that ignored quantization would drift from its receiver", "[codec][coherence]") {
  // The control experiment for the test above: the unquantized model differs from what the receiver decodes.
  const FixedPointQuantizer<double, std::int16_t> wire{0.01};
  DeadbandSender<double, 1, FixedPointQuantizer<double, std::int16_t>> quantized({Mode::predictive, 0.05, 0, 0}, wire);
  DeadbandSender<double, 1> unquantized({Mode::predictive, 0.05, 0, 0});
  NoisySignal<double, 1> signal{Rng(5)};
  int differing = 0;
  for (int k = 0; k < 1000; ++k) {
    const double t = k * 1e-3;
    const auto x = signal.next();
    const auto a = quantized.offer(t, x);
    const auto b = unquantized.offer(t, x);
    differing += !bit_identical(a.value, b.value);
  }
  CHECK(differing > 100);
}

TEST_CASE("both ends switching parameters at the same sample stay coherent", "[codec][coherence]") {
  DeadbandSender<double, 3> sender({Mode::deadband, 0.1, 0.0, 0.0});
  DeadbandReceiver<double, 3> receiver(Mode::deadband);
  NoisySignal<double, 3> signal{Rng(9)};
  for (int k = 0; k < 3000; ++k) {
    const double t = k * 1e-3;
    if (k == 1000) {
      sender.reconfigure({Mode::predictive, 0.05, 0.01, 0.0});
      receiver.set_mode(Mode::predictive);
    }
    if (k == 2000) {
      sender.reconfigure({Mode::deadband, 0.2, 0.0, 25.0});
      receiver.set_mode(Mode::deadband);
    }
    const auto d = sender.offer(t, signal.next());
    if (d.send) receiver.receive(t, d.wire);
    REQUIRE(bit_identical(*receiver.reconstruct(t), d.value));
  }
}

TEST_CASE("the receiver has nothing to show before the first sample", "[codec][coherence]") {
  DeadbandReceiver<double, 1> receiver;
  CHECK_FALSE(receiver.reconstruct(0.0).has_value());
  receiver.receive(0.0, {0.0});
  CHECK(receiver.reconstruct(0.0).has_value());
}

TEST_CASE("fixed-point encoding rounds to nearest and flags saturation instead of wrapping", "[codec][quantizer]") {
  const FixedPointQuantizer<double, std::int16_t> q{0.001};
  bool saturated = false;
  CHECK(q.encode(1.2344, saturated) == 1234);
  CHECK(q.encode(1.2346, saturated) == 1235);
  CHECK(q.encode(-1.2346, saturated) == -1235);
  CHECK(q.encode(32.767, saturated) == 32767);
  CHECK_FALSE(saturated);
  CHECK(q.encode(40.0, saturated) == 32767);
  CHECK(saturated);
  saturated = false;
  CHECK(q.encode(-40.0, saturated) == -32768);
  CHECK(saturated);
  saturated = false;
  CHECK(q.encode(std::nan(""), saturated) == 0);
  CHECK(saturated);
  CHECK(q.decode(-1235) == Approx(-1.235));
}

TEST_CASE("a saturated sample is reported by the sender", "[codec][quantizer]") {
  DeadbandSender<double, 1, FixedPointQuantizer<double, std::int16_t>> sender({}, {0.001});
  const auto d = sender.offer(0.0, {100.0});
  CHECK(d.send);
  CHECK(d.saturated);
  CHECK(d.value[0] == Approx(32.767));
}
