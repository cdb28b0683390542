"""Runs inside Blender (``blender -b --factory-startup --python blender_probe.py -- JOB OUT``):
imports each file of the job with Blender's own importers and records, at every frame, the
world position of every bone's head and tail, the bone names, the frames and the scene's
frame rate. It knows nothing of motionlang (Blender's Python cannot import it);
``blender_check.py`` writes the job and compares.

JOB: JSON ``{"files": [{"id", "path", "format": "bvh" | "gltf", "scale", "fps"}]}``.
``scale`` is the BVH importer's ``global_scale`` (metres per file unit, so that Blender
works in metres); ``fps`` is the scene frame rate set before a glTF import: Blender's glTF
importer puts a key at ``time x scene fps`` and never changes the scene's rate (as a user
sets the scene's rate first), while the BVH importer sets the scene's rate from the file's
Frame Time (``update_scene_fps``).
OUT: JSON with, per id, ``names``, ``frames`` (the keyed frames), ``fps`` (scene frames per
second over the key spacing: the rate Blender plays the keys at), ``heads`` and ``tails``
(frames x bones x 3, Blender world coordinates: Z up, metres).
"""
import json
import math
import sys

import bpy


def _bvh_importer_on_python_311() -> None:
    """Debian's Blender 3.4 runs on the system's Python 3.11, where ``open(path, 'rU')``
    (in the BVH importer's ``read_bvh``) is an error: every BVH import fails with
    "invalid mode: 'rU'". Give that one module an ``open`` that drops the ``U`` (a no-op
    since Python 3.3); nothing else about the importer changes."""
    import builtins

    from io_anim_bvh import import_bvh

    def open_without_u(file, mode="r", *args, **kwargs):
        return builtins.open(file, mode.replace("U", ""), *args, **kwargs)

    import_bvh.open = open_without_u


def keyed_frames(action) -> list:
    return sorted({round(kp.co[0], 4) for fc in action.fcurves for kp in fc.keyframe_points})


def probe(item: dict) -> dict:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    if item["format"] == "bvh":
        _bvh_importer_on_python_311()
        # the importer's own defaults for axes (forward -Z, up Y: Y-up files become Z-up)
        bpy.ops.import_anim.bvh(filepath=item["path"], global_scale=item["scale"],
                                frame_start=1, update_scene_fps=True,
                                update_scene_duration=True)
    else:
        scene.render.fps, scene.render.fps_base = int(round(item["fps"])), 1.0
        # the importer's default shading mode ("NORMALS") calls np.bool, gone from the
        # numpy that Debian's Blender 3.4 runs with: any file with a mesh fails there.
        # Flat shading skips that code, and is what glTF asks for a mesh without normals
        bpy.ops.import_scene.gltf(filepath=item["path"], import_shading="FLAT")
    arms = [o for o in scene.objects if o.type == "ARMATURE"]
    if len(arms) != 1:
        raise SystemExit(f"{item['path']}: {len(arms)} armatures after import")
    arm = arms[0]
    keys = keyed_frames(arm.animation_data.action)
    fps = scene.render.fps / scene.render.fps_base
    step = (keys[-1] - keys[0]) / (len(keys) - 1) if len(keys) > 1 else 0.0
    bones = list(arm.pose.bones)
    heads, tails = [], []
    for k in keys:
        frame = int(math.floor(k))
        scene.frame_set(frame, subframe=k - frame)
        M = arm.matrix_world
        heads.append([list(M @ pb.head) for pb in bones])
        tails.append([list(M @ pb.tail) for pb in bones])
    return {"names": [pb.name for pb in bones], "frames": keys,
            "fps": fps / step if step else fps, "heads": heads, "tails": tails,
            "children": [[c.name for c in pb.children] for pb in bones]}


def main() -> None:
    job_path, out_path = sys.argv[sys.argv.index("--") + 1:][:2]
    with open(job_path, encoding="utf-8") as fh:
        job = json.load(fh)
    result = {item["id"]: probe(item) for item in job["files"]}
    with open(out_path, "w", encoding="utf-8") as fh:
        json.dump(result, fh)


main()
