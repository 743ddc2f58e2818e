// A computed-torque feed-forward in a C++ control loop, calling the generated C.
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "irb140_eom.h"  // extern "C" inside: links with irb140_eom.c

int main()
{
    constexpr int n = IRB140_N;
    std::array<double, n> q{}, qd{}, qdd{}, tau{};
    const int steps = 1000000;
    double checksum = 0.0;
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < steps; ++k) {
        const double t = 1e-3 * k;  // a 1 kHz reference trajectory
        for (int i = 0; i < n; ++i) {
            q[i] = 0.5 * std::sin(t + i);
            qd[i] = 0.5 * std::cos(t + i);
            qdd[i] = -0.5 * std::sin(t + i);
        }
        irb140_tau(q.data(), qd.data(), qdd.data(), tau.data());  // the feed-forward torques [N m]
        checksum += tau[1];
    }
    const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
    std::printf("%.3f us per step (reference + irb140_tau), checksum %g\n", 1e6 * elapsed.count() / steps, checksum);
}
