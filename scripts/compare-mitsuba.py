#!/usr/bin/env python3
"""Peer comparison (issue 5, item 7): the time bounce and Mitsuba 3 (llvm_ad_rgb, CPU) need to reach
relMSE <= 0.02 on the default scene's one-bounce image (direct + one bounce, 128 x 128), on this machine,
in one run.

Each renderer is measured against its own converged image (bounce: --method reference at 4096 spp;
Mitsuba: path tracing at 4096 spp): Mitsuba integrates over each pixel's area while bounce evaluates pixel
centres (the scene contract), so errors against one shared image would be dominated by the edges rather
than the convergence. Mitsuba renders the same OBJ (split per material), camera, point light and diffuse
albedos, with the path integrator at max_depth = 3 (camera edge, direct light, one bounce).

Usage: python3 scripts/compare-mitsuba.py [bounce binary]   (installs mitsuba==3.5.2 with pip if missing)
"""
import os, subprocess, sys, time, tempfile, json, re

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BOUNCE = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "debug", "bounce")
W = H = 128
SCENE = os.path.join(ROOT, "assets", "cornell-box", "scene.toml")
OBJ = os.path.join(ROOT, "assets", "cornell-box", "CornellBox-Original.obj")
MTL = os.path.join(ROOT, "assets", "cornell-box", "CornellBox-Original.mtl")
try:
    import mitsuba as mi
except ImportError:
    subprocess.check_call([sys.executable, "-m", "pip", "install", "-q", "mitsuba==3.5.2", "numpy"])
    import mitsuba as mi
mi.set_variant("llvm_ad_rgb")
try:
    import numpy as np
except ImportError:
    subprocess.check_call([sys.executable, "-m", "pip", "install", "-q", "numpy"])
    import numpy as np

def rel_mse(t, r):
    return float(np.mean((t - r) ** 2 / (r ** 2 + 0.01)))

def split_obj(tmp):
    kd, cur = {}, None
    for line in open(MTL):
        p = line.split()
        if p[:1] == ["newmtl"]: cur = p[1]
        elif p[:1] == ["Kd"] and cur: kd[cur] = [float(x) for x in p[1:4]]
    verts, faces, mat = [], {}, None
    for line in open(OBJ):
        p = line.split()
        if not p: continue
        if p[0] == "v": verts.append(p[1:4])
        elif p[0] == "usemtl": mat = p[1]
        elif p[0] == "f":
            idx = [int(x.split("/")[0]) for x in p[1:]]
            idx = [i if i > 0 else len(verts) + 1 + i for i in idx]
            faces.setdefault(mat, []).append(idx)
    shapes = {}
    for m, fs in faces.items():
        path = os.path.join(tmp, f"{m}.obj")
        with open(path, "w") as f:
            for v in verts: f.write("v " + " ".join(v) + "\n")
            for fc in fs: f.write("f " + " ".join(map(str, fc)) + "\n")
        shapes["shape_" + m] = {"type": "obj", "filename": path, "face_normals": True,
                     "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": kd.get(m, [0.5] * 3)}}}}
    return shapes

def mitsuba_scene(tmp, spp):
    toml = open(SCENE).read()
    vec = lambda k: [float(x) for x in re.search(k + r"\s*=\s*\[([^\]]*)\]", toml).group(1).split(",")]
    fov = float(re.search(r"fov_y\s*=\s*([0-9.]+)", toml).group(1))
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": 3},
         "sensor": {"type": "perspective", "fov": fov, "fov_axis": "y",
                    "to_world": mi.ScalarTransform4f.look_at(origin=vec("eye"), target=vec("target"), up=vec("up")),
                    "sampler": {"type": "independent", "sample_count": spp},
                    "film": {"type": "hdrfilm", "width": W, "height": H, "rfilter": {"type": "box"}, "pixel_format": "rgb"}},
         "point_light_emitter": {"type": "point", "position": vec("position"), "intensity": {"type": "rgb", "value": vec("intensity")}}}
    d.update(split_obj(tmp))
    return mi.load_dict(d)

def mitsuba_render(tmp, spp, seed=0):
    scene = mitsuba_scene(tmp, spp)
    t0 = time.perf_counter()
    img = np.array(mi.render(scene, spp=spp, seed=seed))
    return img[..., :3], time.perf_counter() - t0

def bounce_render(out, spp):
    t0 = time.perf_counter()
    subprocess.check_call([BOUNCE, "render", SCENE, "--width", str(W), "--height", str(H), "--component", "combined",
                           "--method", "reference", "--spp", str(spp), "--out", out], stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    return np.array(mi.Bitmap(out))[..., :3], wall

def main():
    with tempfile.TemporaryDirectory() as tmp:
        mi_ref, t_ref = mitsuba_render(tmp, 4096)
        rows = []
        for spp in [4, 8, 16, 32, 64, 128, 256]:
            img, t = mitsuba_render(tmp, spp, seed=1)
            rows.append(("mitsuba llvm_ad_rgb path (max_depth 3)", spp, t, rel_mse(img, mi_ref)))
        b_ref, _ = bounce_render(os.path.join(tmp, "bref.exr"), 4096)
        for spp in [4, 8, 16, 32, 64, 128, 256]:
            img, t = bounce_render(os.path.join(tmp, f"b{spp}.exr"), spp)
            rows.append(("bounce --method reference (lavapipe)", spp, t, rel_mse(img, b_ref)))
    print(f"| renderer | spp | wall s | relMSE vs its own 4096-spp image |\n|---|---:|---:|---:|")
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]:.3f} | {r[3]:.4g} |")
    for name in sorted(set(r[0] for r in rows)):
        ok = [r for r in rows if r[0] == name and r[3] <= 0.02]
        print(f"\n{name}: first at relMSE <= 0.02: " + (f"{ok[0][1]} spp in {ok[0][2]:.3f} s" if ok else "not reached"))

if __name__ == "__main__":
    main()
