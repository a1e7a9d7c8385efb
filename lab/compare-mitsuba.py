#!/usr/bin/env python3
"""Peer comparison: a one-bounce MIS path tracer written with Mitsuba 3's Python API
against every bounce method, at equal wall time, all judged against the same ground truth.

The Mitsuba tracer computes the indirect component of bounce's scene contract (crates/scene/src/scene):
  L_ind(x) = ∫ albedo(x)/π · L_direct(y → x) cos θ_x dω
at the pixel-centre primary hit x (the camera contract of crates/scene/src/camera.rs), with L_direct(y)
the point lights' direct light at y (two-sided Lambertian, shading normal flipped toward x, exact shadow
rays). Two strategies per sample, combined by the balance heuristic, both densities in area measure at y:
  * cosine sampling at x around the shading normal, first hit y:
        p_c(y) = cos θ_x / π · |cos θ_y| / |x − y|²
  * light-side sampling: a light chosen ∝ power, a uniform direction from it, its first hit y, then a
    shadow ray x ↔ y:  p_l(y) = Σ_l P_l / 4π · |cos θ_{y,l}| · V(l, y) / |l − y|²
Each sample contributes albedo(x) · L_direct(y → x) · p_c / (p_c + p_l) (× V(x, y) for the light side),
which is f / (p_c + p_l): the balance heuristic with one sample per strategy. The 2D samples of both
strategies are jittered-stratified per pixel (an s × s grid when spp = s², Latin hypercube otherwise).

The scene is built in Mitsuba from the same data bounce loads: the OBJ triangulated as fans, positions
made relative to the centre of the bounds (as bounce does), vertex normals when every corner has a `vn`,
else face normals, and one mesh per material whose albedo is a `bitmap` texture holding
Kd × sRGB-decoded texel (NEAREST filter, repeat wrap, v flipped: the contract's lookup) or a constant Kd.

Ground truth per scene: bounce's `--method reference` at --gt-spp with a seed of its own (cached under --out). The script checks
that the Mitsuba tracer converges to it (relMSE and mean ratio at --check-spp), then measures the
Mitsuba tracer's wall time at --spp as a user would (a fresh process: Python start-up, scene build, JIT
and the EXR write included) and runs every bounce method with `--time-limit` = that time. bounce's
start-up (device, scene load, BVH, pipelines) is outside its budget; its whole-process wall time is
reported beside it. Timings depend on the machine's load: indicative only.

Usage: python3 lab/compare-mitsuba.py [--scenes cornell-box,sibenik] [--size 128] [--spp 64]
           [--gt-spp 16384] [--check-spp 1024] [--out target/compare-mitsuba] [--bounce PATH]
(needs `pip install mitsuba==3.5.2 numpy`).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time
import tomllib


ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = ["cornell-box", "two-rooms", "sibenik", "conference"]
METHODS = ["default", "uniform", "global", "stratified", "local", "gbg", "mis", "reference", "ris"]
# Per-frame settings of a method where the render default does not fit a progressive frame. ris runs as
# `bounce render --time-limit T --method ris` does by default: without --vpls it picks its reservoirs and
# candidates per frame for the view itself. `ris-learned` forces the learned visibility (--learn-visibility
# 0.1) at 4 reservoirs of 32 candidates per frame.
METHOD_ARGS = {"ris-learned": ["--vpls", "4", "--candidates", "32", "--learn-visibility", "0.1"]}
# Labels that run another bounce method with their METHOD_ARGS; `default` is `bounce render --time-limit T`
# without --method (and without --spp): what a user gets who asks for the best image in T seconds.
METHOD_OF = {"ris-learned": "ris", "default": None}
DEFAULT_ALBEDO = 0.5
# The ground truth's seed. The compared bounce runs keep the default seed (1); the reference continues one
# Owen-scrambled Sobol sequence per pixel and seed over its progressive frames, so with the ground truth's
# seed its first samples would be the ground truth's own, and its error against it would read low.
GT_SEED = 90001
# Segment visibility ignores hits within this fraction of either end (bounce's BVH_SHADOW_EPS).
SHADOW_EPS = 1e-4


def import_mitsuba():
    try:
        import mitsuba as mi
        import numpy as np  # noqa: F401
    except ImportError:
        sys.exit("needs Mitsuba 3 and numpy: pip install mitsuba==3.5.2 numpy")
    mi.set_variant("llvm_ad_rgb")
    return mi


# ---------------------------------------------------------------------------------------------------
# The scene, read as bounce reads it.

def read_mtl(path):
    """name -> (Kd or None, map_Kd file or None), as bounce's mtl.rs reads them."""
    mats, cur = {}, None
    for line in open(path, encoding="utf-8", errors="replace"):
        code = line.split("#")[0].strip()
        toks = code.split()
        if not toks:
            continue
        if toks[0] == "newmtl":
            cur = code[len("newmtl"):].strip()
            mats[cur] = [None, None]
        elif toks[0] == "Kd" and cur is not None:
            v = [float(t) for t in toks[1:]]
            mats[cur][0] = v * 3 if len(v) == 1 else v[:3]
        elif toks[0] == "map_Kd" and cur is not None:
            mats[cur][1] = toks[-1].replace("\\", "/")
    return {k: (os.path.join(os.path.dirname(path), t) if t else None, kd) for k, (kd, t) in mats.items()}


def read_obj(path):
    """Triangles grouped by material name (None: no material): lists of 3 corners (v, vt, vn)."""
    import numpy as np
    v, vt, vn, groups, mtls, mat = [], [], [], {}, {}, None
    for line in open(path, encoding="utf-8", errors="replace"):
        toks = line.split()
        if not toks:
            continue
        k = toks[0]
        if k == "v":
            v.append([float(t) for t in toks[1:4]])
        elif k == "vt":
            vt.append([float(t) for t in toks[1:3]])
        elif k == "vn":
            vn.append([float(t) for t in toks[1:4]])
        elif k == "mtllib":
            for name in toks[1:]:
                mtls.update(read_mtl(os.path.join(os.path.dirname(path), name)))
        elif k == "usemtl":
            mat = line.strip()[len("usemtl"):].strip()
        elif k == "f":
            corners = []
            for t in toks[1:]:
                idx = (t.split("/") + ["", ""])[:3]
                fix = lambda s, n: (int(s) - 1 if int(s) > 0 else n + int(s)) if s else -1
                corners.append((fix(idx[0], len(v)), fix(idx[1], len(vt)), fix(idx[2], len(vn))))
            # tobj triangulates polygons as fans around the first corner.
            for i in range(1, len(corners) - 1):
                groups.setdefault(mat, []).append([corners[0], corners[i], corners[i + 1]])
    return np.array(v, np.float64), np.array(vt, np.float64), np.array(vn, np.float64), groups, mtls


def load_texture(mi, path, kd):
    """Kd × the sRGB-decoded texels, row 0 = top row of the file, as float32 RGB."""
    import numpy as np
    bmp = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True)
    c = np.array(bmp).astype(np.float32) / np.float32(255.0)
    lin = np.where(c <= 0.04045, c / np.float32(12.92), ((c + np.float32(0.055)) / np.float32(1.055)) ** np.float32(2.4))
    return (lin * np.array(kd, np.float32)).astype(np.float32)


def build_mesh(mi, name, pos, nrm, uv, bsdf):
    import numpy as np
    props = mi.Properties()
    props["bsdf"] = bsdf
    nf = len(pos) // 3
    mesh = mi.Mesh(name, 3 * nf, nf, props, has_vertex_normals=nrm is not None, has_vertex_texcoords=uv is not None)
    p = mi.traverse(mesh)
    p["vertex_positions"] = mi.Float(pos.astype(np.float32).ravel())
    p["faces"] = mi.UInt32(np.arange(3 * nf, dtype=np.uint32))
    if nrm is not None:
        p["vertex_normals"] = mi.Float(nrm.astype(np.float32).ravel())
    if uv is not None:
        p["vertex_texcoords"] = mi.Float(uv.astype(np.float32).ravel())
    p.update()
    return mesh


def material_bsdf(mi, mat, mtls, textures):
    """The albedo of material `mat` as a Mitsuba diffuse BSDF (Kd × texture, or Kd, or the default)."""
    tex, kd = mtls.get(mat, (None, None)) if mat is not None else (None, None)
    if tex is not None:
        kd = kd if kd is not None else [1.0] * 3
        key = (tex, tuple(kd))
        if key not in textures:
            textures[key] = mi.Bitmap(load_texture(mi, tex, kd))
        refl = {"type": "bitmap", "bitmap": textures[key], "raw": True, "filter_type": "nearest", "wrap_mode": "repeat"}
    else:
        refl = {"type": "rgb", "value": kd if kd is not None else [DEFAULT_ALBEDO] * 3}
    return mi.load_dict({"type": "diffuse", "reflectance": refl}), tex is not None


def load_scene(mi, toml_path):
    """(Mitsuba scene, camera dict, lights [(pos, intensity)], diagonal), all relative to the local origin."""
    import numpy as np
    desc = tomllib.load(open(toml_path, "rb"))
    v, vt, vn, groups, mtls = read_obj(os.path.join(os.path.dirname(toml_path), desc["mesh"]))
    used = np.unique(np.array([c[0] for tris in groups.values() for t in tris for c in t]))
    lo, hi = v[used].min(0), v[used].max(0)
    origin = (lo + hi) * 0.5
    shapes, textures = {"type": "scene"}, {}
    for k, (mat, tris) in enumerate(groups.items()):
        idx = np.array(tris)  # (tris, 3 corners, (v, vt, vn))
        pos = v[idx[..., 0]] - origin
        # bounce uses vn only when every corner of the (group, material) mesh has one.
        nrm = None
        if len(vn) and (idx[..., 2] >= 0).all():
            nrm = vn[idx[..., 2]].reshape(-1, 3)
            nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
        bsdf, textured = material_bsdf(mi, mat, mtls, textures)
        uv = None
        if textured and (idx[..., 1] >= 0).all() and len(vt):
            raw = vt[idx[..., 1]].astype(np.float32).reshape(-1, 2)
            # The contract reads texel row floor(fract(1 − v) · h); Mitsuba's row is floor(fract(v') · h).
            uv = np.stack([raw[:, 0], np.float32(1.0) - raw[:, 1]], 1)
        shapes[f"mesh{k}"] = build_mesh(mi, f"mesh{k}", pos.reshape(-1, 3), nrm, uv, bsdf)
    cam = {key: np.array(desc["camera"][key], np.float64) for key in ("eye", "target", "up")}
    cam["eye"] -= origin
    cam["target"] -= origin
    cam["fov_y"] = float(desc["camera"]["fov_y"])
    lights = [(np.array(l["position"], np.float64) - origin, np.array(l["intensity"], np.float64)) for l in desc["light"]]
    return mi.load_dict(shapes), cam, lights, float(np.linalg.norm(hi - lo))


# ---------------------------------------------------------------------------------------------------
# The one-bounce MIS tracer.

def camera_rays(cam, w, h):
    """Unit directions through the pixel centres (row-major, row 0 = top), as Camera::ray_dir_f in f32."""
    import numpy as np
    f = np.float32
    eye, target, up = (cam[k].astype(f) for k in ("eye", "target", "up"))
    norm = lambda a: a / np.linalg.norm(a, axis=-1, keepdims=True).astype(f)
    fwd = norm(target - eye)
    right = norm(np.cross(fwd, up))
    true_up = np.cross(right, fwd)
    t = f(math.tan(math.radians(cam["fov_y"]) * 0.5))
    x, y = np.meshgrid(np.arange(w, dtype=f) + f(0.5), np.arange(h, dtype=f) + f(0.5))
    ndc_x = x / f(w) * f(2) - f(1)
    ndc_y = f(1) - y / f(h) * f(2)
    d = fwd + (ndc_x * t * (f(w) / f(h)))[..., None] * right + (ndc_y * t)[..., None] * true_up
    return eye, norm(d.reshape(-1, 3)).astype(f)


class Tracer:
    """The estimator of the module docstring over a Mitsuba scene (llvm variant, wavefront batches)."""

    def __init__(self, mi, scene, lights, diagonal):
        import drjit as dr
        self.mi, self.dr, self.scene, self.diag = mi, dr, scene, diagonal
        power = [float(sum(i)) for _, i in lights]
        self.lights = [(mi.Point3f(*map(float, p)), mi.Color3f(*map(float, i)), pw / sum(power))
                       for (p, i), pw in zip(lights, power)]

    def v3(self, a, cls):
        return cls(*(self.mi.Float(a[:, c]) for c in range(3)))

    def lift(self, p, ng, d):
        """p moved off its surface to the side d points to (bounce's surface_lift, along the geometric normal)."""
        dr = self.dr
        a = dr.abs(p)
        lift = dr.maximum(1e-5 * self.diag, dr.maximum(a.x, dr.maximum(a.y, a.z)) * (1.0 / 262144.0))
        return p + ng * dr.select(dr.dot(ng, d) >= 0, lift, -lift)

    def clear(self, p, ng, q, active):
        """Whether the segment p → q is unoccluded (hits within SHADOW_EPS of q ignored)."""
        o = self.lift(p, ng, q - p)
        return ~self.scene.ray_test(self.mi.Ray3f(o, q - o, 1.0 - SHADOW_EPS, 0.0, []), active)

    def surface(self, si, toward):
        """(position, geometric and shading normals flipped toward `toward`, albedo) of a hit."""
        dr = self.dr
        v = toward - si.p
        ng = dr.select(dr.dot(si.n, v) < 0, -si.n, si.n)
        ns = dr.select(dr.dot(si.sh_frame.n, v) < 0, -si.sh_frame.n, si.sh_frame.n)
        return si.p, ng, ns, si.bsdf().eval_diffuse_reflectance(si, si.is_valid())

    def direct(self, y, ngy, ny, ay, active, chosen=None):
        """(L_direct(y) toward the side of ny, the light-side density p_l(y) in area measure). `chosen`:
        the light whose first hit y is (visible by construction)."""
        dr, mi = self.dr, self.mi
        radiance, pl = mi.Color3f(0.0), mi.Float(0.0)
        for k, (lp, intensity, prob) in enumerate(self.lights):
            to = lp - y
            d2 = dr.squared_norm(to)
            dist = dr.sqrt(d2)
            ok = active & (d2 > 0)
            # dr.neq / dr.eq, not != / ==: on Dr.Jit 0.4 arrays those compare whole arrays (one bool),
            # which made every multi-light scene's light side shoot from the first light.
            need = ok if chosen is None else ok & dr.neq(chosen, k)
            vis = ok & dr.select(need, self.clear(y, ngy, lp, need), True)
            c = dr.dot(ny, to) / dist
            radiance += dr.select(vis & (c > 0), ay * intensity * (c / (math.pi * d2)), 0.0)
            pl += dr.select(vis, prob / (4.0 * math.pi) * dr.abs(dr.dot(ngy, to)) / (dist * d2), 0.0)
        return radiance, pl

    def cosine_side(self, x, n, ng, ax, u):
        dr, mi = self.dr, self.mi
        d = mi.Frame3f(n).to_world(mi.warp.square_to_cosine_hemisphere(u))
        si = self.scene.ray_intersect(mi.Ray3f(self.lift(x, ng, d), d))
        hit = si.is_valid()
        y, ngy, ny, ay = self.surface(si, x)
        radiance, pl = self.direct(y, ngy, ny, ay, hit)
        pc = dr.dot(n, d) / math.pi * dr.abs(dr.dot(ngy, d)) / dr.squared_norm(y - x)
        return dr.select(hit & (pc > 0), ax * radiance * (pc / (pc + pl)), 0.0)

    def light_side(self, x, n, ng, ax, u, chosen):
        dr, mi = self.dr, self.mi
        lp = self.lights[0][0]
        for k in range(1, len(self.lights)):
            lp = dr.select(dr.eq(chosen, k), self.lights[k][0], lp)
        si = self.scene.ray_intersect(mi.Ray3f(lp, mi.warp.square_to_uniform_sphere(u)))
        y, ngy, ny, ay = self.surface(si, x)
        to = y - x
        r2 = dr.squared_norm(to)
        cos_x = dr.dot(n, to) / dr.sqrt(r2)
        front = si.is_valid() & (cos_x > 0)
        seen = front & self.clear(x, ng, y, front)
        radiance, pl = self.direct(y, ngy, ny, ay, seen, chosen)
        pc = cos_x / math.pi * dr.abs(dr.dot(ngy, to)) / (dr.sqrt(r2) * r2)
        return dr.select(seen & (pl > 0), ax * radiance * (pc / (pc + pl)), 0.0)

    def primary(self, eye, dirs):
        """Per pixel: hit mask and numpy (x, n, ng, albedo) of the pixel-centre primary hits."""
        import numpy as np
        mi = self.mi
        eye_p = mi.Point3f(*map(float, eye))
        si = self.scene.ray_intersect(mi.Ray3f(eye_p, self.v3(dirs, mi.Vector3f)))
        x, ng, n, ax = self.surface(si, eye_p)
        cols = lambda v: np.stack([np.array(v.x), np.array(v.y), np.array(v.z)], 1)
        albedo = np.stack([np.array(ax.x), np.array(ax.y), np.array(ax.z)], 1)
        return np.array(si.is_valid()), cols(x), cols(n), cols(ng), albedo

    def render(self, cam, w, h, spp, seed):
        """The indirect image (h, w, 3): spp samples of each strategy per pixel, jittered-stratified."""
        import numpy as np
        mi = self.mi
        eye, dirs = camera_rays(cam, w, h)
        hit, x, n, ng, ax = self.primary(eye, dirs)
        pix = np.nonzero(hit)[0]
        out = np.zeros((w * h, 3), np.float64)
        if len(pix) == 0:
            return out.reshape(h, w, 3).astype(np.float32)
        rng = np.random.default_rng(seed)
        side = math.isqrt(spp)
        batch = max(1, min(spp, (1 << 19) // len(pix)))
        probs = np.cumsum([l[2] for l in self.lights])
        for k0 in range(0, spp, batch):
            ks = np.arange(k0, min(spp, k0 + batch))
            lanes = len(pix) * len(ks)
            k = np.tile(ks, len(pix))
            # The s × s grid of strata for the first s² samples; any rest is uniform (still unbiased).
            def stratified():
                j = rng.random((2, lanes), dtype=np.float32)
                grid = k < side * side
                return mi.Point2f(np.where(grid, ((k % side) + j[0]) / side, j[0]).astype(np.float32),
                                  np.where(grid, ((k // side) + j[1]) / side, j[1]).astype(np.float32))
            rep = lambda a, cls: self.v3(np.repeat(a[pix], len(ks), axis=0), cls)
            xs, ns, ngs = rep(x, mi.Point3f), rep(n, mi.Vector3f), rep(ng, mi.Vector3f)
            axs = rep(ax, mi.Color3f)
            chosen = mi.UInt32(np.searchsorted(probs, rng.random(lanes), side="right").clip(0, len(probs) - 1).astype(np.uint32))
            c = self.cosine_side(xs, ns, ngs, axs, stratified()) + self.light_side(xs, ns, ngs, axs, stratified(), chosen)
            vals = np.stack([np.array(c.x), np.array(c.y), np.array(c.z)], 1).astype(np.float64)
            out[pix] += vals.reshape(len(pix), len(ks), 3).sum(1)
        return (out / spp).reshape(h, w, 3).astype(np.float32)


def mitsuba_render(scene_path, size, spp, seed, exr):
    """One render as a user would run it (this is what the parent times, in a fresh process)."""
    t0 = time.perf_counter()
    mi = import_mitsuba()
    t1 = time.perf_counter()
    scene, cam, lights, diag = load_scene(mi, scene_path)
    t2 = time.perf_counter()
    img = Tracer(mi, scene, lights, diag).render(cam, size, size, spp, seed)
    t3 = time.perf_counter()
    mi.Bitmap(img).write(exr)
    print(json.dumps({"import_s": t1 - t0, "load_s": t2 - t1, "render_s": t3 - t2}))


# ---------------------------------------------------------------------------------------------------
# The comparison.

def compare(bounce, test, ref):
    """bounce's own metrics of `test` against `ref` (relMSE = mean (t − r)² / (r² + 0.01), mean ratio)."""
    out = subprocess.run([bounce, "compare", test, ref, "--json"], check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def run_timed(cmd):
    t0 = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if out.returncode != 0:
        sys.exit(f"failed ({out.returncode}): {' '.join(cmd)}\n{out.stderr}")
    return wall, out


def bounce_cmd(a, scene_path, exr, method, extra):
    """`bounce render` of the indirect component; method None: the command's default."""
    return [a.bounce, "render", scene_path, "--width", str(a.size), "--height", str(a.size),
            "--component", "indirect", "--out", exr] + (["--method", method] if method else []) + extra


def ground_truth(a, name, scene_path):
    """bounce's --method reference at --gt-spp with its own seed (GT_SEED), cached under --out."""
    exr = os.path.join(a.out, f"{name}-{a.size}-gt{a.gt_spp}-seed{GT_SEED}.exr")
    if os.path.exists(exr):
        print(f"ground truth: {exr} (cached)")
    else:
        extra = ["--spp", str(a.gt_spp), "--seed", str(GT_SEED)]
        wall, _ = run_timed(bounce_cmd(a, scene_path, exr, "reference", extra))
        print(f"ground truth: {exr} (bounce --method reference --spp {a.gt_spp}, {wall:.1f} s)")
    return exr


def mitsuba_timed(a, name, scene_path, spp, seed):
    """(whole-process wall s, in-process timings, EXR) of one Mitsuba tracer render in a fresh process."""
    exr = os.path.join(a.out, f"{name}-{a.size}-mitsuba{spp}.exr")
    cmd = [sys.executable, os.path.abspath(__file__), "--mitsuba-render", scene_path, "--size", str(a.size),
           "--spp", str(spp), "--seed", str(seed), "--exr", exr]
    wall, out = run_timed(cmd)
    return wall, json.loads(out.stdout.strip().splitlines()[-1]), exr


def exr_meta(mi, path):
    meta = mi.Bitmap(path).metadata()
    return {k: meta[k] for k in meta.property_names()}


def run_scene(a, mi, name):
    scene_path = os.path.join(ROOT, "assets", name, "scene.toml")
    print(f"\n## {name}, {a.size}², indirect component\n")
    gt = ground_truth(a, name, scene_path)
    _, _, check = mitsuba_timed(a, name, scene_path, a.check_spp, a.seed + 1)
    m = compare(a.bounce, check, gt)
    verdict = "converges to it" if abs(m["mean_ratio"] - 1) <= 0.03 else "CONTRACT MISMATCH (mean off by more than 3 %)"
    print(f"Mitsuba MIS tracer at {a.check_spp} spp against the ground truth: relMSE {m['rel_mse']:.4g}, "
          f"mean ratio {m['mean_ratio']:.4f}: {verdict} (that relMSE also bounds the ground truth's own noise, "
          f"which every relMSE below includes)")
    wall, inner, exr = mitsuba_timed(a, name, scene_path, a.spp, a.seed)
    mref = compare(a.bounce, exr, gt)
    print(f"Mitsuba MIS tracer, {a.spp} spp: {wall:.2f} s wall (process: import {inner['import_s']:.2f} s, "
          f"scene build {inner['load_s']:.2f} s, render + JIT {inner['render_s']:.2f} s). "
          f"Dr.Jit's kernels come from its disk cache once compiled (the check above compiles them), as on a "
          f"user's second run. bounce methods get --time-limit {wall:.2f}; their start-up (device, scene, BVH, "
          f"pipelines) is outside it: the last column is each bounce process's whole wall time.\n")
    rows = [(f"Mitsuba MIS ({a.spp} spp)", wall, "-", mref, wall)]
    for method in a.methods:
        out_exr = os.path.join(a.out, f"{name}-{a.size}-{method}.exr")
        extra = ["--time-limit", f"{wall:.3f}"] + (["--spp", str(a.ref_frame_spp)] if method == "reference" else []) + METHOD_ARGS.get(method, [])
        whole, _ = run_timed(bounce_cmd(a, scene_path, out_exr, METHOD_OF.get(method, method), extra))
        meta = exr_meta(mi, out_exr)
        rows.append((f"bounce {method}", float(meta.get("bounce.wall_s", "nan")), meta.get("bounce.frames", "?"),
                     compare(a.bounce, out_exr, gt), whole))
    print("| method | wall s | frames | relMSE vs ground truth | mean ratio | relMSE / Mitsuba's | process wall s |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for label, w, frames, met, whole in rows:
        print(f"| {label} | {w:.2f} | {frames} | {met['rel_mse']:.4g} | {met['mean_ratio']:.4f} | "
              f"{met['rel_mse'] / mref['rel_mse']:.2f} | {whole:.2f} |")
    sys.stdout.flush()


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scenes", default=",".join(SCENES), help="comma-separated subset of " + ",".join(SCENES))
    p.add_argument("--size", type=int, default=128, help="image width and height")
    p.add_argument("--spp", type=int, default=64, help="Mitsuba tracer samples per pixel (sets the time budget)")
    p.add_argument("--gt-spp", type=int, default=16384, help="samples per pixel of the ground truth")
    p.add_argument("--check-spp", type=int, default=1024, help="Mitsuba samples of the convergence check")
    p.add_argument("--ref-frame-spp", type=int, default=16, help="spp per progressive frame of bounce's reference")
    p.add_argument("--methods", default=",".join(METHODS),
                   help="bounce methods to run (also: " + ", ".join(METHOD_OF) + ")")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default=os.path.join(ROOT, "target", "compare-mitsuba"), help="cache and output folder")
    p.add_argument("--bounce", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "debug", "bounce"))
    p.add_argument("--mitsuba-render", metavar="SCENE", help=argparse.SUPPRESS)
    p.add_argument("--exr", help=argparse.SUPPRESS)
    a = p.parse_args()
    if a.mitsuba_render:
        return mitsuba_render(a.mitsuba_render, a.size, a.spp, a.seed, a.exr)
    a.methods = [m for m in a.methods.split(",") if m]
    if not os.access(a.bounce, os.X_OK):
        sys.exit(f"no bounce binary at {a.bounce}: build it (cargo build -p bounce) or pass --bounce")
    os.makedirs(a.out, exist_ok=True)
    mi = import_mitsuba()
    print(f"Mitsuba {mi.__version__} (llvm_ad_rgb) against bounce ({a.bounce}); {os.cpu_count()} CPU cores; "
          "timings depend on the machine's load and are indicative.")
    for name in a.scenes.split(","):
        run_scene(a, mi, name)


if __name__ == "__main__":
    main()
