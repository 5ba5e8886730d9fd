#!/usr/bin/env python3
"""Open3D's ScalableTSDFVolume on the same frames as `iscene bench tsdf`, side by side.

Integrates the selected 7-Scenes-layout frames (frame-NNNNNN.{color.jpg,depth.png,pose.txt})
minus every N-th (held out) with Open3D, timing integration alone with frames already decoded,
as iscene's benchmark does. Then raycasts both systems' meshes from every held-out pose with
Open3D's RaycastingScene, one method for both, and compares with the measured depth.
Prints one JSON object and a table with the speed ratio.
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import open3d as o3d

MAX_DEPTH_M = 5.0  # iscene's max ray length
DEPTH_SCALE = 1000.0
BATCH = 64


def frame_paths(root: Path, start: int, end, step: int):
    depths = sorted(root.glob("frame-*.depth.png"))
    stems = [p.name[: -len(".depth.png")] for p in depths]
    stems = stems[start:end:step]
    return [(root / f"{s}.color.jpg", root / f"{s}.depth.png", root / f"{s}.pose.txt") for s in stems]


def intrinsics(root: Path):
    path = root / "camera-intrinsics.txt"
    k = np.loadtxt(path) if path.exists() else np.array([[585.0, 0, 320], [0, 585.0, 240], [0, 0, 1]])
    return o3d.camera.PinholeCameraIntrinsic(640, 480, k[0, 0], k[1, 1], k[0, 2], k[1, 2]), k


def load_rgbd(color_path, depth_path):
    color = o3d.io.read_image(str(color_path))
    depth = o3d.io.read_image(str(depth_path))
    return o3d.geometry.RGBDImage.create_from_color_and_depth(
        color, depth, depth_scale=DEPTH_SCALE, depth_trunc=MAX_DEPTH_M, convert_rgb_to_intensity=False
    )


def integrate_once(keep, intrinsic, voxel):
    """A fresh volume with every frame of `keep` fused; integration alone is timed."""
    volume = o3d.pipelines.integration.ScalableTSDFVolume(
        voxel_length=voxel,
        sdf_trunc=4.0 * voxel,  # iscene's truncation band: four voxels
        color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8,
    )
    load_s, integrate_s = 0.0, 0.0
    for b in range(0, len(keep), BATCH):
        clock = time.perf_counter()
        batch = [(load_rgbd(c, d), np.loadtxt(p)) for c, d, p in keep[b : b + BATCH]]
        load_s += time.perf_counter() - clock
        clock = time.perf_counter()
        for rgbd, world_from_camera in batch:
            volume.integrate(rgbd, intrinsic, np.linalg.inv(world_from_camera))
        integrate_s += time.perf_counter() - clock
    return volume, load_s, integrate_s


def integrate(frames, intrinsic, voxel, held_out, runs):
    """`runs` integrations into fresh volumes (the fastest counts, as in `iscene bench tsdf
    --runs`), then the last volume's mesh."""
    keep = [f for i, f in enumerate(frames) if not held_out(i)]
    load_s, run_s, volume = 0.0, [], None
    for _ in range(runs):
        volume = None  # the previous run's volume goes first, as iscene's does
        volume, load, integrate_s = integrate_once(keep, intrinsic, voxel)
        load_s += load
        run_s.append(integrate_s)
    clock = time.perf_counter()
    mesh = volume.extract_triangle_mesh()
    mesh_s = time.perf_counter() - clock
    return mesh, len(keep), load_s, run_s, mesh_s


def agreement(mesh_paths, frames, k, held_out, pixel_step=2):
    """|measured depth - depth raycast on each mesh| over held-out frames' pixels: over the pixels
    each mesh hits, and over the pixels every mesh hits (the like-for-like figure)."""
    scenes = []
    for path in mesh_paths:
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.t.io.read_triangle_mesh(str(path)))
        scenes.append(scene)
    v, u = np.mgrid[0:480:pixel_step, 0:640:pixel_step]
    dirs_cam = np.stack([(u - k[0, 2]) / k[0, 0], (v - k[1, 2]) / k[1, 1], np.ones_like(u, dtype=float)], -1)
    residuals = [[] for _ in scenes]
    evaluated = 0
    for i, (_, depth_path, pose_path) in enumerate(frames):
        if not held_out(i):
            continue
        evaluated += 1
        pose = np.loadtxt(pose_path)
        depth = np.asarray(o3d.io.read_image(str(depth_path)), dtype=np.float64)[::pixel_step, ::pixel_step] / DEPTH_SCALE
        valid = (depth > 0) & (depth <= MAX_DEPTH_M)
        # Unnormalised directions with unit z in the camera: the hit distance is the depth.
        dirs = dirs_cam[valid] @ pose[:3, :3].T
        origins = np.broadcast_to(pose[:3, 3], dirs.shape)
        rays = o3d.core.Tensor(np.concatenate([origins, dirs], 1).astype(np.float32))
        for r, scene in zip(residuals, scenes):
            r.append(np.abs(depth[valid] - scene.cast_rays(rays)["t_hit"].numpy()))
    out = []
    per_mesh = [np.concatenate(r) for r in residuals]
    common = np.logical_and.reduce([np.isfinite(r) for r in per_mesh])
    for r in per_mesh:
        hit = r[np.isfinite(r)]
        out.append({
            "frames": evaluated,
            "pixels": int(hit.size),
            "misses": int(r.size - hit.size),
            "median_m": float(np.median(hit)),
            "mean_m": float(hit.mean()),
            "p90_m": float(np.quantile(hit, 0.9)),
            "common_pixels": int(common.sum()),
            "common_median_m": float(np.median(r[common])),
            "common_mean_m": float(r[common].mean()),
        })
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("sequence", type=Path)
    ap.add_argument("--frames", default="0:300", help="A:B[:STEP], as iscene's --frames")
    ap.add_argument("--voxel", type=float, default=0.02)
    ap.add_argument("--holdout", type=int, default=10)
    ap.add_argument("--runs", type=int, default=1, help="integrations; the fastest is reported")
    ap.add_argument("--mesh", type=Path, required=True, help="where to write Open3D's mesh")
    ap.add_argument("--iscene-json", type=Path, required=True, help="`iscene bench tsdf` output")
    ap.add_argument("--iscene-mesh", type=Path, required=True, help="its --mesh")
    args = ap.parse_args()

    parts = args.frames.split(":")
    start = int(parts[0] or 0)
    end = int(parts[1]) if len(parts) > 1 and parts[1] else None
    step = int(parts[2]) if len(parts) > 2 else 1
    frames = frame_paths(args.sequence, start, end, step)
    if not frames:
        sys.exit(f"{args.sequence}: no frame-*.depth.png frames selected by {args.frames}")
    intrinsic, k = intrinsics(args.sequence)
    n = args.holdout

    def held_out(i):
        return n > 0 and i % n == n - 1

    mesh, fused, load_s, run_s, mesh_s = integrate(frames, intrinsic, args.voxel, held_out, max(args.runs, 1))
    integrate_s = min(run_s)
    o3d.io.write_triangle_mesh(str(args.mesh), mesh)
    ours = json.loads(args.iscene_json.read_text())
    if ours["frames_fused"] != fused:
        sys.exit(f"frame sets differ: iscene fused {ours['frames_fused']}, Open3D {fused}")
    open3d = {
        "version": o3d.__version__,
        "frames_fused": fused,
        "load_s": load_s,
        "integrate_s": integrate_s,
        "integrate_runs_s": run_s,
        "integrate_frames_per_s": fused / integrate_s,
        "mesh_s": mesh_s,
        "mesh_vertices": len(mesh.vertices),
    }
    ours["held_out_on_mesh"], open3d["held_out_on_mesh"] = agreement(
        [args.iscene_mesh, args.mesh], frames, k, held_out
    )
    result = {
        "voxel_m": args.voxel,
        "frames": args.frames,
        "iscene": ours,
        "open3d": open3d,
        "speed_ratio": ours["integrate_frames_per_s"] / open3d["integrate_frames_per_s"],
    }
    print(json.dumps(result, indent=2))
    print(
        f"# voxel {args.voxel * 100:.0f} cm, {fused} frames fused: "
        f"iscene {ours['integrate_frames_per_s']:.1f} frames/s (labels: {ours['labels']}), "
        f"Open3D {open3d['integrate_frames_per_s']:.1f} frames/s, ratio {result['speed_ratio']:.2f}x; "
        f"held-out median |depth - mesh raycast| where both meshes are hit: "
        f"iscene {ours['held_out_on_mesh']['common_median_m'] * 1000:.2f} mm, "
        f"Open3D {open3d['held_out_on_mesh']['common_median_m'] * 1000:.2f} mm "
        f"(misses: iscene {ours['held_out_on_mesh']['misses']}, Open3D {open3d['held_out_on_mesh']['misses']})",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
