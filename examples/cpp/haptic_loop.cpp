// A 1 kHz haptic servo loop on innersphere's C ABI, as a C++ haptic application runs it.
//
//   haptic_loop A.ist B.ist MOTION.csv [--rate HZ] [--class omega|touch]
//
// The device is stood in for by a motion CSV (t,tx,ty,tz,qw,qx,qy,qz: the handle's pose of
// body B in A's frame, mm and s); where a real device SDK plugs in is marked DEVICE. A
// servo thread ticks at the rate with std::chrono::steady_clock and sleep_until, calls
// ist_haptic_tick, "sends" the force, and counts deadline misses; a 60 Hz graphics thread
// reads the latest tool pose through a lock-free handoff (a seqlock of atomics). At the end
// it prints the rate reached, the tick times, the deadline misses (ticks that ended after
// their deadline, whoever is to blame) and the ticks over budget (the tick's own compute
// took longer than its budget: the library's share).
#include "innersphere.h"
#include "chai3d_tool.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#ifdef __linux__
#include <pthread.h>
#include <sched.h>
#endif

using Clock = std::chrono::steady_clock;

// The tool pose handed from the servo thread to the graphics thread without a lock: the
// writer makes the sequence odd, stores, makes it even; the reader retries while it is odd
// or changed.
class PoseHandoff {
  public:
    void publish(const ist_pose& p) {
        uint64_t s = seq_.load(std::memory_order_relaxed);
        seq_.store(s + 1, std::memory_order_relaxed);
        std::atomic_thread_fence(std::memory_order_release);
        for (int i = 0; i < 3; i++) v_[i].store(p.t[i], std::memory_order_relaxed);
        for (int i = 0; i < 4; i++) v_[3 + i].store(p.q[i], std::memory_order_relaxed);
        seq_.store(s + 2, std::memory_order_release);
    }
    bool read(ist_pose& p) const {
        for (;;) {
            uint64_t s0 = seq_.load(std::memory_order_acquire);
            if (s0 == 0) return false;
            if (s0 & 1) continue;
            for (int i = 0; i < 3; i++) p.t[i] = v_[i].load(std::memory_order_relaxed);
            for (int i = 0; i < 4; i++) p.q[i] = v_[3 + i].load(std::memory_order_relaxed);
            std::atomic_thread_fence(std::memory_order_acquire);
            if (seq_.load(std::memory_order_relaxed) == s0) return true;
        }
    }

  private:
    std::atomic<uint64_t> seq_{0};
    std::atomic<double> v_[7];
};

static std::vector<ist_pose> read_motion(const char* path) {
    std::ifstream f(path);
    std::vector<ist_pose> poses;
    std::string line;
    std::getline(f, line);  // header
    while (std::getline(f, line)) {
        std::istringstream s(line);
        std::string cell;
        double x[8];
        int n = 0;
        while (n < 8 && std::getline(s, cell, ',')) x[n++] = std::strtod(cell.c_str(), nullptr);
        if (n != 8) continue;
        ist_pose p{{x[1], x[2], x[3]}, {x[4], x[5], x[6], x[7]}};
        poses.push_back(p);
    }
    return poses;
}

int main(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: %s A.ist B.ist MOTION.csv [--rate HZ] [--class omega|touch]\n",
                     argv[0]);
        return 2;
    }
    double rate = 1000.0;
    int device_class = IST_DEVICE_OMEGA;
    for (int i = 4; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--rate")) rate = std::atof(argv[i + 1]);
        if (!std::strcmp(argv[i], "--class"))
            device_class = std::strcmp(argv[i + 1], "touch") ? IST_DEVICE_OMEGA : IST_DEVICE_TOUCH;
    }
    ist_tree* a = ist_tree_load(argv[1]);
    ist_tree* b = ist_tree_load(argv[2]);
    if (!a || !b) {
        std::fprintf(stderr, "error: %s\n", ist_last_error());
        return 1;
    }
    std::vector<ist_pose> motion = read_motion(argv[3]);  // recorded at 1 kHz
    if (motion.empty()) {
        std::fprintf(stderr, "error: no poses in %s\n", argv[3]);
        return 1;
    }
    ist_pair* pair = ist_pair_new(a, b);
    ist_haptic_params params;
    ist_haptic_params_default(device_class, &params);
    params.rate = rate;
    params.budget = 1.0 / rate;
    params.start = motion[0];
    ist_haptic* haptic = ist_haptic_new(pair, &params);
    if (!haptic) {
        std::fprintf(stderr, "error: %s\n", ist_last_error());
        return 1;
    }

    const size_t ticks = static_cast<size_t>(std::floor((motion.size() - 1) / 1000.0 * rate)) + 1;
    std::vector<double> tick_us(ticks);  // allocated before the loop: the loop allocates nothing
    size_t misses = 0;       // ticks that ended after their deadline
    size_t over_budget = 0;  // ticks whose own compute took longer than the budget
    size_t budgeted = 0;
    double max_dt = 0.0;
    double max_force = 0.0;
    PoseHandoff handoff;
    std::atomic<bool> running{true};
    std::atomic<size_t> frames{0};

    std::thread graphics([&] {  // 60 Hz: draw the tool where the servo thread last put it
        auto next = Clock::now();
        ist_pose tool;
        while (running.load(std::memory_order_relaxed)) {
            next += std::chrono::microseconds(16667);
            std::this_thread::sleep_until(next);
            if (handoff.read(tool)) frames.fetch_add(1, std::memory_order_relaxed);  // draw(tool)
        }
    });

    // Servo threads ask for real-time scheduling (CHAI3D and the device SDKs do): without it
    // any other thread can delay a tick. Best effort: it needs root or CAP_SYS_NICE.
    bool realtime = false;
#ifdef __linux__
    sched_param sp{};
    sp.sched_priority = 20;
    realtime = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) == 0;
#endif
    auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate));
    auto start = Clock::now();
    auto deadline = start;
    auto last = start;
    for (size_t i = 0; i < ticks; i++) {
        deadline += period;
        auto t0 = Clock::now();
        // DEVICE: read the handle's pose here (e.g. dhdGetPositionAndOrientationFrame, or
        // hdGetDoublev(HD_CURRENT_TRANSFORM) + ist_pose_from_matrix(m, 1, &pose)). The
        // stand-in plays the recording in real time, so that a late tick sees the motion of
        // the time it missed, as a real device would.
        double now_s = std::chrono::duration<double>(t0 - start).count();
        const ist_pose& device =
            motion[std::min(motion.size() - 1, static_cast<size_t>(std::lround(now_s * 1000.0)))];
        double dt = std::chrono::duration<double>(t0 - last).count();
        last = t0;
        ist_haptic_output out;
        if (ist_haptic_tick(haptic, &device, i == 0 ? 0.0 : dt, &out) != IST_OK) {
            std::fprintf(stderr, "tick %zu: %s\n", i, ist_last_error());
        }
        auto t1 = Clock::now();
        // DEVICE: send out.force (N) and out.torque (N*mm) here (e.g. dhdSetForceAndTorque).
        max_force = std::max(max_force, std::sqrt(out.force[0] * out.force[0] +
                                                  out.force[1] * out.force[1] +
                                                  out.force[2] * out.force[2]));
        budgeted += out.budgeted;
        if (i > 0) max_dt = std::max(max_dt, dt);
        handoff.publish(out.tool);
        tick_us[i] = std::chrono::duration<double, std::micro>(t1 - t0).count();
        if (t1 > deadline) misses++;
        if (out.late) over_budget++;
        // Sleep until shortly before the next tick, then spin: sleep_until alone wakes up
        // to a few hundred microseconds late on a loaded or virtual machine.
        std::this_thread::sleep_until(deadline - std::chrono::microseconds(600));
        while (Clock::now() < deadline) {
        }
    }
    double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    running = false;
    graphics.join();

    std::vector<double> sorted = tick_us;
    std::sort(sorted.begin(), sorted.end());
    auto pct = [&](double q) { return sorted[static_cast<size_t>(std::lround((sorted.size() - 1) * q))]; };
    double energy = 0.0, energy_max = 0.0;
    ist_haptic_energy(haptic, &energy, &energy_max);
    std::printf(
        "{\"ticks\": %zu, \"rate_hz\": %.1f, \"achieved_hz\": %.1f, \"deadline_misses\": %zu, \"over_budget\": %zu, "
        "\"tick_p50_us\": %.2f, \"tick_p99_us\": %.2f, \"tick_max_us\": %.2f, \"max_force_n\": %.4f, "
        "\"energy_to_user_max_j\": %.3e, \"graphics_frames\": %zu, \"budgeted_ticks\": %zu, \"max_dt_ms\": %.3f, \"realtime\": %s}\n",
        ticks, rate, ticks / seconds, misses, over_budget, pct(0.5), pct(0.99), sorted.back(), max_force,
        energy_max, frames.load(), budgeted, max_dt * 1e3, realtime ? "true" : "false");

    innersphere_example::compile_check_chai3d_adapter(pair, params);
    ist_haptic_free(haptic);
    ist_pair_free(pair);
    ist_tree_free(a);
    ist_tree_free(b);
    return 0;
}
