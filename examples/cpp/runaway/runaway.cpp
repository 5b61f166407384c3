// The paper's runaway skill in C++: if the nearest obstacle is closer than
// safe_distance, back away from it and turn away. The typed I/O comes from
// `situate gen cpp runaway.yaml` (cpp_runaway.hpp). It counts the cycles it ran
// away from each switch on (on_activate) and says the count when switched off
// (on_deactivate), as the Rust, C and Python versions do.
#include <cmath>
#include <cstdint>
#include <string>

#include "cpp_runaway.hpp"

class Runaway : public cpp_runaway::Skill {
 public:
  // Switched on: counts afresh (the object lives across activations).
  void on_activate(situate::Context& /*cx*/) { ran_ = 0; }

  void step(const Inputs& in, Outputs& out, const Params& params, situate::Context& /*cx*/) {
    constexpr int kSonars = 24;
    const double two_pi = 2.0 * 3.14159265358979323846;
    double r_min = static_cast<double>(in.sonar.range[0]);
    int k = 0;
    for (int i = 1; i < kSonars; i++) {
      const double r = static_cast<double>(in.sonar.range[i]);
      if (r < r_min) {  // ties: the lowest index wins
        r_min = r;
        k = i;
      }
    }
    if (r_min >= params.safe_distance) {
      return;  // nothing near: write nothing
    }
    const double a = k <= 12 ? k * two_pi / kSonars : k * two_pi / kSonars - two_pi;
    out.drive.v = -0.3 * std::cos(a) * (1.0 - r_min / params.safe_distance);
    out.drive.w = -1.0 * std::sin(a);
    out.has_drive = true;
    ++ran_;
  }

  // Switched off: says how long it ran away while on.
  void on_deactivate(situate::Context& cx) {
    cx.print("switched off after running away " + std::to_string(ran_) + " cycles");
  }

 private:
  std::uint64_t ran_ = 0;  // cycles it ran away since it was last switched on
};

SITUATE_CPP_LIBRARY(Runaway)
