#!/usr/bin/env bash
# Where a lavapipe render's time goes, function by function of the JIT-compiled shaders. perf sees
# llvmpipe's generated code only as anonymous addresses; this samples the render with `perf record`,
# copies the executable mapping that holds the hottest sample from /proc/<pid>/mem, disassembles it
# (objdump) and splits the samples by function. llvmpipe compiles a texel fetch of most formats into a
# function of its own, called from the shader, so the fetches' share shows separately from the
# shader's body (BENCHMARKS.md, "Where the exact gather's time goes").
#
# Linux only. Needs perf (Debian: linux-perf), objdump (binutils) and python3, and the rights to
# sample and read a child process (root, or kernel.perf_event_paranoid ≤ 1 with ptrace allowed).
# Usage: lab/profile-jit.sh <delay s> <window s> <bounce render arguments...>
#   e.g. lab/profile-jit.sh 3 3 assets/sibenik/scene.toml --width 512 --height 256 \
#        --component indirect --dprsm-res 32 --method uniform --vpls 256 --visibility exact
# The render must still be running after delay + window seconds (make it large enough); the delay
# skips the pipelines' compilation. Prints a table; leaves its files in ${TMPDIR:-/tmp}/bounce-jit.*
set -euo pipefail
[ $# -ge 3 ] || { echo "error: usage: lab/profile-jit.sh <delay s> <window s> <bounce render arguments...>" >&2; exit 2; }
delay="$1" window="$2"
shift 2
for tool in perf objdump python3; do
  command -v "$tool" >/dev/null || { echo "error: $tool is not installed" >&2; exit 1; }
done
here="$(cd "$(dirname "$0")/.." && pwd)"
cargo build -q --release -p bounce --manifest-path "$here/Cargo.toml"
bin="${CARGO_TARGET_DIR:-$here/target}/release/bounce"
work="$(mktemp -d "${TMPDIR:-/tmp}/bounce-jit.XXXXXX")"
"$bin" render "$@" --out "$work/render.exr" >"$work/render.log" 2>&1 &
pid=$!
# Stop the render if anything below fails; after a normal end it has been waited for.
trap 'kill "$pid" 2>/dev/null || true' EXIT
sleep "$delay"
kill -0 "$pid" 2>/dev/null || { echo "error: the render ended within the delay (see $work/render.log)" >&2; exit 1; }
perf record -q -F 4000 -o "$work/perf.data" -p "$pid" -- sleep "$window" >/dev/null 2>&1
perf report -i "$work/perf.data" --sort sym --stdio 2>/dev/null | grep '\[\.\]' >"$work/samples.txt" || true
python3 - "$pid" "$work" <<'PY'
import bisect, re, subprocess, sys
pid, work = sys.argv[1], sys.argv[2]
samples = {}
for line in open(f"{work}/samples.txt"):
    m = re.match(r"\s*([\d.]+)%\s+\[\.\]\s+0x([0-9a-f]+)\s*$", line)
    if m:
        samples[int(m.group(2), 16)] = float(m.group(1))
if not samples:
    sys.exit("error: perf recorded no samples in JIT code (is the render still running after the delay?)")
hottest = max(samples, key=samples.get)
region = None
for line in open(f"/proc/{pid}/maps"):
    lo, hi = (int(x, 16) for x in line.split()[0].split("-"))
    if lo <= hottest < hi and "x" in line.split()[1]:
        region = (lo, hi)
if region is None:
    sys.exit("error: the hottest sample is in no executable mapping of the render (it ended too soon?)")
lo, hi = region
with open(f"/proc/{pid}/mem", "rb") as mem:
    mem.seek(lo)
    open(f"{work}/jit.bin", "wb").write(mem.read(hi - lo))
asm = subprocess.run(["objdump", "-D", "-b", "binary", "-mi386:x86-64", f"--adjust-vma={lo:#x}", f"{work}/jit.bin"],
                     capture_output=True, text=True, check=True).stdout
open(f"{work}/jit.asm", "w").write(asm)
# A function runs from just after one `ret` to the next.
rets = sorted(int(m.group(1), 16) for m in re.finditer(r"^\s*([0-9a-f]+):\t[^\n]*\tret", asm, re.M))
starts = [lo] + [r + 1 for r in rets]
share, outside = {}, 0.0
for a, p in samples.items():
    if not lo <= a < hi:
        outside += p
        continue
    s = starts[bisect.bisect_right(starts, a) - 1]
    share[s] = share.get(s, 0.0) + p
total = sum(samples.values())
print(f"{total:.1f} % of the samples at unnamed (JIT) addresses; {outside:.1f} % outside the copied mapping")
print("| function (address) | bytes | share of all samples |")
print("|---|---:|---:|")
for s, p in sorted(share.items(), key=lambda kv: -kv[1])[:8]:
    end = next((r for r in rets if r >= s), hi - 1) + 1
    print(f"| {s:#x} | {end - s} | {p:.1f} % |")
print(f"files: {work} (samples.txt, jit.asm)")
PY
wait "$pid" || true
