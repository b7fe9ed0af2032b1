"""Issue 27 item 1: andyc's forward dynamics per call against Pinocchio's own C++ aba, no Python binding in the way.

Compiles bench/pinocchio_aba.cpp once into build/bench/ (g++ -O3 -march=native against the pin wheel's headers and
libraries under cmeel.prefix; Eigen from Debian's libeigen3-dev, else the cmeel-eigen wheel; the URDF headers from
the cmeel-urdfdom-headers wheel: both wheels are in the bench extra, which `make bench` installs), then for each
robot alternates rounds of andyc's rhs in a compiled loop (bench/large.py's AndycForward), the C++ aba
(instantiated in that file, -march=native), the wheel's libpinocchio_default aba called from C++ ("lib", what
pin.aba runs), and pin.aba from Python. us per call, min .. max over rounds; ratios within a round. Before timing,
the C++ aba's accelerations at its (random) state are checked against pin.aba's from Python at the same state.
Without g++, Eigen or the headers: one line, no timing.

    python bench/pinocchio_cpp.py                      ur5, panda, solo12, g1
    python bench/pinocchio_cpp.py --robot talos_full   (its andyc build takes minutes)
    python bench/large.py --cpp                        the C++ lines within large.py's robot section
"""

from __future__ import annotations

import argparse
import hashlib
import shutil
import subprocess
import sysconfig
import tempfile
from pathlib import Path

import numpy as np

from large import ROBOTS, AndycForward, _ratios, _spread, build_robot, compare, pin_forward

ROOT = Path(__file__).resolve().parents[1]
SOURCE = Path(__file__).with_name("pinocchio_aba.cpp")
DEFINES = ["NDEBUG", "PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION", "PINOCCHIO_WITH_URDFDOM",
           "PINOCCHIO_URDFDOM_HEADERS_MAJOR_VERSION=3", "PINOCCHIO_URDFDOM_HEADERS_MINOR_VERSION=0",
           "PINOCCHIO_URDFDOM_HEADERS_PATCH_VERSION=0", "BOOST_MPL_LIMIT_LIST_SIZE=30", "BOOST_MPL_LIMIT_VECTOR_SIZE=30",
           "BOOST_MPL_CFG_NO_PREPROCESSED_HEADERS", "BOOST_FUSION_INVOKE_MAX_ARITY=12",
           # the wheel's libraries are built for SSE2: Eigen's layouts and heap alignment must stay theirs under AVX
           "EIGEN_MAX_ALIGN_BYTES=16", "EIGEN_MALLOC_ALREADY_ALIGNED=1"]


def compile_command(out: Path):
    """The g++ command line that builds the timing program into `out`, or a one-line reason why it cannot."""
    prefix = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix"
    eigen = next((d for d in (Path("/usr/include/eigen3"), Path("/usr/local/include/eigen3"),
                              prefix / "include" / "eigen3") if (d / "Eigen" / "Core").exists()), None)
    missing = [what for what, ok in (
        ("g++", shutil.which("g++")), ("Eigen (apt-get install libeigen3-dev, or pip install cmeel-eigen)", eigen),
        ("Pinocchio's C++ headers (pip install pin)", (prefix / "include" / "pinocchio" / "algorithm" / "aba.hpp").exists()),
        ("urdfdom's headers (pip install cmeel-urdfdom-headers)",
         (prefix / "include" / "urdfdom_headers" / "urdf_model" / "model.h").exists())) if not ok]
    if missing:
        return None, "no " + ", no ".join(missing)
    lib = prefix / "lib"
    return (["g++", "-std=c++17", "-O3", "-march=native", *(f"-D{d}" for d in DEFINES), f"-I{prefix / 'include'}",
             f"-I{prefix / 'include' / 'urdfdom_headers'}", f"-I{eigen}", str(SOURCE), "-o", str(out), f"-L{lib}",
             f"-Wl,-rpath,{lib}", "-lpinocchio_parsers", "-lpinocchio_default", "-lurdfdom_model"], None)


def build(cache: Path = ROOT / "build" / "bench"):
    """(path of the compiled program, None), compiled once per source and command line; or (None, why not)."""
    command, why = compile_command(Path("OUT"))
    if command is None:
        return None, why
    key = hashlib.sha256(SOURCE.read_bytes() + " ".join(command).encode()).hexdigest()[:12]
    exe = cache / f"pinocchio_aba-{key}"
    if not exe.exists():
        cache.mkdir(parents=True, exist_ok=True)
        print("compiling bench/pinocchio_aba.cpp (about a minute): " + " ".join(command).replace("OUT", str(exe)),
              flush=True)
        done = subprocess.run(["nice", "-n", "19"] + [str(exe) if c == "OUT" else c for c in command],
                              capture_output=True, text=True)
        if done.returncode:
            errors = [line for line in done.stderr.splitlines() if "error" in line] or done.stderr.splitlines()
            return None, "g++ failed: " + (errors[0] if errors else f"exit {done.returncode}")
    return exe, None


class CppAba:
    """The C++ program serving one URDF: its state (q, v, tau) and ddq, and per-round timers of its aba."""

    def __init__(self, exe: Path, urdf: Path, base: str):
        self.proc = subprocess.Popen([str(exe), str(urdf), base, "serve"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True)
        self.state = {}
        while "ddq" not in self.state:
            line = self.proc.stdout.readline()
            if not line:
                raise RuntimeError(f"{exe} {urdf} {base} ended with code {self.proc.wait()}")
            name, *values = line.split()
            if name != "nq":                    # (the first line: "nq NQ nv NV")
                self.state[name] = np.array(values, dtype=float)

    def timer(self, which: str):
        """us per call of aba over n calls, `which` = native (this program's instance) or lib (the wheel's)."""
        def run(n):
            self.proc.stdin.write(f"{n} {which}\n")
            self.proc.stdin.flush()
            return float(self.proc.stdout.readline().split()[2])
        return run

    def close(self):
        self.proc.stdin.close()
        self.proc.wait()


def same_as_python(pmodel, cpp: CppAba) -> str:
    """The C++ aba's ddq against pin.aba's from Python at the C++ program's state."""
    import pinocchio as pin
    s = cpp.state
    ddq = pin.aba(pmodel, pmodel.createData(), s["q"], s["v"], s["tau"])
    return f"C++ ddq = pin.aba's to {abs(ddq - s['ddq']).max():.1e} (max |ddq| {abs(ddq).max():.2g})"


def timers(cpp: CppAba) -> dict:
    return {"cpp": cpp.timer("native"), "lib": cpp.timer("lib")}


def summary(times: dict, pmodel, cpp: CppAba) -> str:
    """One line: the C++ figures from `times` (andyc, cpp, lib), the ratio, the check against pin.aba."""
    return (f"Pinocchio C++ aba {_spread(times['cpp'])} us, andyc/C++ aba {_spread(_ratios(times, 'andyc', 'cpp'))}"
            f"; the wheel's lib aba from C++ {_spread(times['lib'])} us; {same_as_python(pmodel, cpp)}")


def run(names=("ur5", "panda", "solo12", "g1"), rounds: int = 5, calls: int = 50000) -> None:
    """Per robot: andyc rhs, C++ aba, lib aba and pin.aba from Python, alternated over `rounds` rounds."""
    exe, why = build()
    if exe is None:
        print(f"Pinocchio C++ aba: skipped, {why}")
        return
    from andyc.independent.robots import robots_dir
    print(f"us per call over {calls} calls, min .. max over {rounds} alternated rounds; ratios within a round. "
          "C++ aba: bench/pinocchio_aba.cpp (-O3 -march=native); lib: the wheel's libpinocchio_default from C++")
    with tempfile.TemporaryDirectory() as tmpdir:
        for name in names:
            path, base = ROBOTS[name]
            urdf = robots_dir() / path
            model, _, seconds, pmodel = build_robot(Path(tmpdir), urdf, base)
            cpp = CppAba(exe, urdf, base)
            try:
                times = compare({"andyc": AndycForward(model), **timers(cpp),
                                 "pin": pin_forward(pmodel, cpp.state["q"], cpp.state["v"])}, rounds, calls)
            finally:
                cpp.close()
            print(f"{name} ({base} base, nv {pmodel.nv}, andyc build {seconds:.0f} s, formulation "
                  f"{model.module.FORMULATION}): andyc rhs {_spread(times['andyc'])} us, pin.aba from Python "
                  f"{_spread(times['pin'])} us, andyc/pin.aba {_spread(_ratios(times, 'andyc', 'pin'))}", flush=True)
            print("  " + summary(times, pmodel, cpp), flush=True)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", choices=tuple(ROBOTS), nargs="*", default=["ur5", "panda", "solo12", "g1"])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--calls", type=int, default=50000, help="calls per round and timer")
    args = parser.parse_args(argv)
    run(args.robot, args.rounds, args.calls)


if __name__ == "__main__":
    main()
