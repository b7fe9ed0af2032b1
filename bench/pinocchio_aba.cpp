// Pinocchio's own C++ cost of the articulated-body algorithm (pinocchio::aba), no Python binding in the way.
// Issue 27 item 1; compiled and driven by bench/pinocchio_cpp.py, which shows the command line.
//
//   pinocchio_aba URDF fixed|floating [CALLS [ROUNDS]]     CALLS aba calls per round (100000), ROUNDS rounds (5)
//   pinocchio_aba URDF fixed|floating serve                 one round per line "CALLS native|lib" read from stdin
//
// Two builds of the same algorithm are timed: "native", aba instantiated in this file (g++ -O3 -march=native),
// and "lib", the instance compiled into libpinocchio_default (what pin.aba calls from Python), reached through
// the Eigen::Ref arguments it was instantiated for. State: a random configuration within the joint limits (the
// unbounded ones taken as [-1, 1]), random v and tau (seed 0). Each call moves q[0] by 1e-12 so that nothing is
// hoisted. Output lines, parseable: "nq nv", then q, v, tau and ddq = aba(q, v, tau) at that state (%.17g), then per
// round "round native|lib US" (us per call) and, in the batch form, "min native US", "max native US", likewise lib.
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

using Vector = Eigen::VectorXd;
using Ref = Eigen::Ref<const Vector>;

static void print(const char * name, const Vector & x)
{
  std::printf("%s", name);
  for (Eigen::Index i = 0; i < x.size(); ++i)
    std::printf(" %.17g", x[i]);
  std::printf("\n");
}

// us per call of aba over `calls` calls; lib: the library's instance (Eigen::Ref arguments), else this file's.
static double round_us(
  const pinocchio::Model & model, pinocchio::Data & data, Vector & q, const Vector & v, const Vector & tau,
  long calls, bool lib, double & sink)
{
  const Ref qr(q), vr(v), taur(tau);   // views: q[0]'s change below is seen through qr
  const auto tic = std::chrono::steady_clock::now();
  for (long k = 0; k < calls; ++k)
  {
    q[0] += 1e-12;
    if (lib)
      pinocchio::aba(model, data, qr, vr, taur);
    else
      pinocchio::aba(model, data, q, v, tau);
    sink += data.ddq[0];
  }
  const std::chrono::duration<double, std::micro> us = std::chrono::steady_clock::now() - tic;
  return us.count() / double(calls);
}

int main(int argc, char ** argv)
{
  if (argc < 3)
  {
    std::fprintf(stderr, "usage: %s URDF fixed|floating [CALLS [ROUNDS] | serve]\n", argv[0]);
    return 2;
  }
  const std::string urdf = argv[1], base = argv[2];
  const bool serve = argc > 3 && std::string(argv[3]) == "serve";
  const long calls = argc > 3 && !serve ? std::atol(argv[3]) : 100000;
  const int rounds = argc > 4 ? std::atoi(argv[4]) : 5;

  pinocchio::Model model;
  if (base == "floating")
    pinocchio::urdf::buildModel(urdf, pinocchio::JointModelFreeFlyer(), model);
  else
    pinocchio::urdf::buildModel(urdf, model);
  pinocchio::Data data(model);

  std::srand(0);
  Vector lower = model.lowerPositionLimit, upper = model.upperPositionLimit;
  for (Eigen::Index i = 0; i < model.nq; ++i)
    if (!(lower[i] > -1e10 && upper[i] < 1e10 && lower[i] <= upper[i]))
      lower[i] = -1.0, upper[i] = 1.0;
  Vector q = pinocchio::randomConfiguration(model, lower, upper);
  const Vector v = Vector::Random(model.nv), tau = Vector::Random(model.nv);

  std::printf("nq %d nv %d\n", model.nq, model.nv);
  print("q", q);
  print("v", v);
  print("tau", tau);
  print("ddq", pinocchio::aba(model, data, q, v, tau));
  const Vector q0 = q;

  double sink = 0.0;
  round_us(model, data, q, v, tau, std::max(1L, calls / 10), false, sink);   // warm up both
  round_us(model, data, q, v, tau, std::max(1L, calls / 10), true, sink);
  if (serve)
  {
    std::fflush(stdout);
    long n;
    std::string which;
    while (std::cin >> n >> which)
    {
      q = q0;
      std::printf("round %s %.6g\n", which.c_str(), round_us(model, data, q, v, tau, n, which == "lib", sink));
      std::fflush(stdout);
    }
  }
  else
  {
    std::vector<double> times[2];
    for (int r = 0; r < rounds; ++r)
      for (int lib = 0; lib < 2; ++lib)
      {
        q = q0;
        times[lib].push_back(round_us(model, data, q, v, tau, calls, lib, sink));
        std::printf("round %s %.6g\n", lib ? "lib" : "native", times[lib].back());
      }
    for (int lib = 0; lib < 2; ++lib)
    {
      const char * name = lib ? "lib" : "native";
      std::printf("min %s %.6g\n", name, *std::min_element(times[lib].begin(), times[lib].end()));
      std::printf("max %s %.6g\n", name, *std::max_element(times[lib].begin(), times[lib].end()));
    }
  }
  if (!serve)
    std::fprintf(stderr, "sink %g\n", sink);   // (uses the results, so that no call is dropped)
  return 0;
}
