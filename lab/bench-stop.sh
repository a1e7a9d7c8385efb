#!/usr/bin/env bash
# The viewer's stop (passes/present.rs, `Prior`): for every scene folder given, a camera walk, `realtime`
# along it (its last, denoised frame D is what the viewer showed when the view stopped), 64 still frames
# of ris at its end (what the viewer then accumulates) and the end view's path-traced truth (1024 spp,
# kept in OUT), then `stop-blend`'s table: the displayed mean's relMSE after n still frames for each
# prior weight W and fade N0 (W = 0: the plain mean), and the stop's jump. The walk: the folder's
# camera-path.toml (24 frames), else 16 frames that go 15 % of the way to the target while the view
# turns (the generated suite's scenes). Last, the aggregate over the folders of each (W, N0) over W = 0.
# Usage: lab/bench-stop.sh OUT SCENE_DIR...   (SIZE=64 by default; BOUNCE=path/to/bounce measures that build)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
out="$1"
shift
size="${SIZE:-64}"
if [ -z "${BOUNCE:-}" ]; then (cd "$here" && cargo build -q -p bounce); fi
bin="${BOUNCE:-${CARGO_TARGET_DIR:-$here/target}/debug/bounce}"
(cd "$here" && cargo build -q --release -p bounce-lab --bin stop-blend)
blend="${CARGO_TARGET_DIR:-$here/target}/release/stop-blend"
common=(--width "$size" --height "$size" --dprsm-res 128 --component indirect)
end_file=""
trap 'rm -f "$end_file"' EXIT
for dir in "$@"; do
  name="$(basename "$dir")"
  end_file="$dir/.stop-end.toml"
  o="$out/$name"
  mkdir -p "$o"
  # The walk (o/walk.toml) and the scene at its end (dir/.stop-end.toml, beside the scene's own files).
  frames="$(python3 - "$dir" "$o/walk.toml" <<'PY'
import re, sys
d, walk = sys.argv[1], sys.argv[2]
scene = open(f"{d}/scene.toml").read()
vec = lambda text, k: [float(x) for x in re.findall(rf"^{k}\s*=\s*\[([^\]]*)\]", text, re.M)[-1].split(",")]
fmt = lambda a: "[" + ", ".join(repr(x) for x in a) + "]"
try:
    path = open(f"{d}/camera-path.toml").read()
    e2, g2 = vec(path, "eye"), vec(path, "target")
    frames = int(re.findall(r"^frame\s*=\s*(\d+)", path, re.M)[-1]) + 1
    open(walk, "w").write(path)
except FileNotFoundError:
    e, g = vec(scene, "eye"), vec(scene, "target")
    v = [g[i] - e[i] for i in range(3)]
    side = [v[2], 0.0, -v[0]]
    e2 = [e[i] + 0.15 * v[i] for i in range(3)]
    g2 = [g[i] + 0.15 * side[i] for i in range(3)]
    frames = 16
    open(walk, "w").write(f"[[key]]\nframe = 0\neye = {fmt(e)}\ntarget = {fmt(g)}\n\n[[key]]\nframe = 15\neye = {fmt(e2)}\ntarget = {fmt(g2)}\n")
end = re.sub(r"^eye\s*=.*$", f"eye = {fmt(e2)}", scene, count=1, flags=re.M)
end = re.sub(r"^target\s*=.*$", f"target = {fmt(g2)}", end, count=1, flags=re.M)
open(f"{d}/.stop-end.toml", "w").write(end)
print(frames)
PY
)"
  rm -rf "$o/rt" "$o/still"
  "$bin" render "$dir/scene.toml" --method realtime --camera-path "$o/walk.toml" --frames "$frames" "${common[@]}" \
    --out-dir "$o/rt" >/dev/null 2>&1
  "$bin" render "$dir/.stop-end.toml" --method ris --vpls 64 --frames 64 "${common[@]}" --out-dir "$o/still" >/dev/null 2>&1
  [ -f "$o/truth.exr" ] || "$bin" render "$dir/.stop-end.toml" --method reference --spp 1024 "${common[@]}" \
    --out "$o/truth.exr" >/dev/null 2>&1
  rm -f "$dir/.stop-end.toml"
  last="$(printf 'frame_%04d.exr' $((frames - 1)))"
  "$blend" "$o/rt/$last" "$o/still" "$o/truth.exr" >"$o/blend.md"
  echo "## $name"
  cat "$o/blend.md"
done
# The aggregate: per (W, N0), the geometric mean and worst case over the folders of its jump, relMSE at
# n = 1 and 4 and mean relMSE over the 64 frames, each over W = 0's.
python3 - "$out" "$@" <<'PY'
import math, os, sys
out, names = sys.argv[1], [os.path.basename(d.rstrip("/")) for d in sys.argv[2:]]
rows = {}
for n in names:
    for line in open(f"{out}/{n}/blend.md"):
        c = [x.strip() for x in line.strip().strip("|").split("|")]
        if not line.startswith("| ") or c[0] == "W":
            continue
        rows.setdefault((c[0], c[1]), {})[n] = [float(c[2]), float(c[3]), float(c[5]), float(c[-2])]
gm = lambda xs: math.exp(sum(math.log(max(x, 1e-12)) for x in xs) / len(xs))
base = rows[("0", "inf")]
print(f"\n## Over {len(names)} views, each over W = 0 (geometric mean / worst)\n")
print("| W | N0 | jump | n = 1 | n = 4 | mean over the frames |")
print("|---|---|---:|---:|---:|---:|")
for key, per in rows.items():
    if key == ("0", "inf"):
        continue
    r = [[per[n][i] / base[n][i] for n in names if base[n][i] > 0] for i in range(4)]
    print(f"| {key[0]} | {key[1]} | {gm(r[0]):.3f} | {gm(r[1]):.3f} / {max(r[1]):.2f} | {gm(r[2]):.3f} / {max(r[2]):.2f} | {gm(r[3]):.3f} / {max(r[3]):.2f} |")
PY
