"""Body positions -> a ``Motion`` on a user's rig (their skeleton, joint names, units and
rest pose), so that a generated motion drops onto their character.

The body is K points (the 21-joint body ``features.joint_map.KIT21_NAMES``, point 0 its
root) given as ``W @ joint positions`` of the rig (``W`` (K, J), each used row summing to
1: a joint, a midpoint, a lerp). Only joints whose rotation is a full 3-axis Euler chain
("free" joints: BVH's 3 rotation channels, ASF's ``rx ry rz``) are solved, in topological
order; every other joint keeps its local rotation from one template frame of the rig (its
first frame by default: a rig's zero-rotation pose need not be a standing one, Bandai's
bones all lie along local X).

* A free joint's targets are the body points on joints it reaches first going down (through
  unmapped joints such as a clavicle or a twist bone). Their rest vectors come from the
  template frame, with those in-between joints at their template rotation. They are aimed
  at from where the body has the joint (the rig's joint moved by its offset from the
  body's nearest mapped joint), so bones take the body's directions and keep the rig's
  lengths instead of bending to reach the body's absolute positions. An unmapped joint's
  offset is shortened where the body's segment to its targets is shorter than the rig's,
  so that a long in-between link (CMU BVH's Neck -> Neck1 -> Head) never aims from beyond
  its target.
* Targets with no free joint in between ("direct") are matched first: Kabsch on them when
  they span two directions; else the smallest swing of the template-relative orientation
  onto the longest one, then the twist about it that best fits the other targets. The
  in-between joints are solved in their turn and correct the indirect targets, so a rig's
  own motion comes back exactly as long as its unmapped joints stay as in the template
  (with ``ground``, raised where its toe tips would go below the floor of its mapped
  points).
* A single direction with nothing to fix the twist keeps the template's twist; near the
  half turn from the template direction, where that twist is ill defined, the twist is
  carried over from the previous frame instead (blended, so there are no flips).
* The root: the same fit on vectors from the root body point, which pins the translation.
  With ``ground`` the rig then stands on the source's floor (its lowest drawn point, toe
  tips and end sites below the mapped joints included, on the source's lowest body point;
  5th percentiles over frames) and its travel is scaled by the ratio of hip heights, so that
  longer or shorter legs neither float, sink nor slide.

Euler angles follow the branch and the 2 pi multiple nearest the previous frame (the
template's for the first frame), so BVH curves neither jump nor flip near gimbal lock.
Joints with 1 or 2 DOFs (MMM, ASF hinges) cannot be aimed and are refused where a body
point lies below them. Kinematics does not import features: callers pass ``W``
(``features.joint_map.kit21_weights(rig.skeleton)[1]`` for the built-in maps).
"""
from __future__ import annotations

import numpy as np

from motionlang.errors import MotionlangError, SkeletonError
from motionlang.kinematics.from_positions import _kabsch, _swing, _unit
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.rotations import (
    chain,
    expmap_to_matrix,
    matrix_to_chain,
    matrix_to_expmap,
)
from motionlang.kinematics.skeleton import Skeleton

#: meta entries that describe the template's file, not the retargeted motion (the BVH
#: reader's spread of animated inner position channels is a measurement of that file)
PER_FILE_META = ("path", "frame_time", "first_frame", "sequence", "bvh_position_spread_m")


def _free(axes: np.ndarray) -> bool:
    """True for 3 distinct coordinate axes: a chain that can represent any rotation."""
    idx = np.argmax(np.abs(axes), axis=1) if len(axes) == 3 else []
    return len(set(map(int, idx))) == 3 and np.allclose(np.abs(axes).max(axis=1), 1.0)


def _plan(sk: Skeleton, W: np.ndarray) -> list[tuple[np.ndarray, np.ndarray] | None]:
    """Per joint: (body point indices (n,), direct (n,) bool) it aims at, or None."""
    J, support = len(sk), [set(np.flatnonzero(row).tolist()) for row in W]
    mapped = (W != 0).any(axis=0)
    free = [_free(sk.root_axes if j == 0 else jt.axes) for j, jt in enumerate(sk.joints)]
    kids = [sk.children(j) for j in range(J)]
    below = np.zeros(J, dtype=bool)              # a mapped joint strictly below
    for j in range(J - 1, -1, -1):
        below[j] = any(mapped[c] or below[c] for c in kids[j])
    for j, jt in enumerate(sk.joints[1:], start=1):
        if jt.ndof and not free[j] and below[j]:
            raise SkeletonError(f"cannot retarget onto {sk.name!r}: joint {jt.name!r} has "
                                f"{jt.ndof} rotation DOF(s), not a 3-axis Euler chain, and "
                                "body points below it (hinge joints cannot be aimed)")
    if not free[0]:
        raise SkeletonError(f"cannot retarget onto {sk.name!r}: its root rotation is not a "
                            "3-axis Euler chain")
    plan: list[tuple[np.ndarray, np.ndarray] | None] = [None] * J
    for j in range(J):
        if not free[j]:
            continue
        first, stack = {}, [(c, True) for c in kids[j]]
        while stack:                              # down to the first mapped free joints
            s, direct = stack.pop()
            if mapped[s]:
                first[s] = direct
            if not (mapped[s] and free[s]):
                stack.extend((c, direct and not free[s]) for c in kids[s])
        ks = [k for k, sup in enumerate(support)
              if sup and sup <= first.keys() | {j} and (sup != {j} or j == 0)]
        if ks:
            plan[j] = (np.array(ks), np.array([all(first.get(s, True) for s in support[k])
                                               for k in ks]))
    reached = set().union(*(set(p[0].tolist()) for p in plan if p is not None))
    lost = [k for k, sup in enumerate(support) if sup and k not in reached]
    if plan[0] is None or lost:
        raise SkeletonError(f"cannot retarget onto {sk.name!r}: " + (
            f"body points {lost} lie on joints that no single joint reaches" if lost else
            "its root reaches no body point"))
    return plan


def _twist_fit(G: np.ndarray, u: np.ndarray, rest: np.ndarray, target: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """Turn G (T, 3, 3) about unit u (T, 3) to best carry ``rest`` (m, 3) onto ``target``
    (T, m, 3); -> G and a (T,) mask of frames where the targets said nothing of the twist.

    Targets close to the axis only partly decide it (a fraction growing from 0 to 1 as
    their lever goes from 2 % to 10 % of their length): noise in a nearly straight chain
    (a foot's mid-foot point) must not spin the joint."""
    c = np.einsum("tij,mj->tmi", G, rest)
    cp = c - np.sum(c * u[:, None], -1, keepdims=True) * u[:, None]
    bp = target - np.sum(target * u[:, None], -1, keepdims=True) * u[:, None]
    x = np.sum(bp * cp, axis=(1, 2))
    y = np.sum(bp * np.cross(u[:, None], cp), axis=(1, 2))
    size = np.sum(np.linalg.norm(target, axis=-1) * np.linalg.norm(c, axis=-1), axis=1)
    lever = np.hypot(x, y) / np.maximum(size, 1e-12)
    weight = np.clip((lever - 0.02) / 0.08, 0.0, 1.0)
    turn = expmap_to_matrix(u * (weight * np.arctan2(y, x))[:, None])
    return turn @ G, weight == 0.0


def _keep_twist(G: np.ndarray, free: np.ndarray, base: np.ndarray, L: np.ndarray,
                a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Where the template's twist is ill defined (the bone ``a`` (3,) more than 120 degrees
    from its template direction ``base @ L @ a``), take the previous frame's rotation
    relative to ``base`` (T, 3, 3), swung onto ``b`` (T, 3), turned part way (none at 155
    degrees and beyond) towards G's twist."""
    v, _ = _unit(np.einsum("tij,j->ti", base @ L, a))
    u, _ = _unit(b)
    alpha = np.clip((np.sum(u * v, axis=-1) + 0.9) / 0.4, 0.0, 1.0)
    for t in np.flatnonzero(free & (alpha < 1.0)):
        if t == 0:
            continue
        Gc = base[t] @ base[t - 1].T @ G[t - 1]
        Gc = _swing(_unit(Gc @ a)[0][None], u[t][None])[0] @ Gc
        phi = matrix_to_expmap(G[t] @ Gc.T) @ u[t]
        G[t] = expmap_to_matrix(u[t] * alpha[t] * phi) @ Gc
    return G


def _fit(rest: np.ndarray, target: np.ndarray, direct: np.ndarray, base: np.ndarray,
         L: np.ndarray) -> np.ndarray:
    """World rotations (T, 3, 3) carrying rest vectors (n, 3) onto targets (T, n, 3),
    direct ones first; ``base @ L`` is the template-relative reference orientation."""
    ref = base @ L
    if len(rest) == 0:
        return ref
    prim = direct if direct.any() else np.ones(len(rest), dtype=bool)
    sv = np.linalg.svd(rest[prim], compute_uv=False)
    ok = np.zeros(len(target), dtype=bool)
    if len(sv) >= 2 and sv[1] > 1e-3 * sv[0]:
        G_k, ok = _kabsch(rest[prim], target[:, prim])
        if ok.all():
            return G_k
    i = int(np.argmax(np.linalg.norm(rest, axis=1) * prim))
    u, has = _unit(target[:, i])
    G = _swing(_unit(np.einsum("tij,j->ti", ref, rest[i]))[0], u) @ ref
    G[~has] = ref[~has]                           # a target on the joint: no direction
    others = np.arange(len(rest)) != i
    G, loose = _twist_fit(G, u, rest[others], target[:, others])
    if ok.any():
        G[ok] = G_k[ok]
    return _keep_twist(G, has & loose & ~ok, base, L, rest[i], target[:, i])


def _unmapped_origin(origin: np.ndarray, P: np.ndarray, start: np.ndarray,
                     rig_reach: np.ndarray, ks: np.ndarray) -> np.ndarray:
    """Where an unmapped joint aims from (T, 3): ``origin``, the body's point ``start``
    (T, 3) of its nearest mapped ancestor plus the rig's offset to the joint, drawn towards
    ``start`` where the body's segments from ``start`` to the joint's targets ``ks`` are
    shorter than the rig's (``rig_reach`` (n, 3), template). Without that, a rig whose
    in-between link is longer than the body's whole segment (CMU BVH: Neck -> Neck1 ->
    Head against the body's short BLN -> BUN) aims from beyond its target and points the
    bone backwards. A body as long as the rig, its own motion included, keeps ``origin``."""
    body = np.linalg.norm(P[:, ks] - start[:, None], axis=-1)          # (T, n)
    rig = np.linalg.norm(rig_reach, axis=-1)                             # (n,)
    ratio = np.min(body / np.maximum(rig, 1e-9), axis=1, initial=1.0)   # (T,)
    return start + np.minimum(ratio, 1.0)[:, None] * (origin - start)


def _solve(P: np.ndarray, W: np.ndarray, sk: Skeleton, plan: list, Gt: np.ndarray,
           Xt: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """World rotations (T, J, 3, 3), positions (T, J, 3) in the source frame, and the body
    point that pins the root, for targets P (T, K, 3) (source frame, metres)."""
    T, J = len(P), len(sk)
    G, X, E = np.empty((T, J, 3, 3)), np.empty((T, J, 3)), np.zeros((T, J, 3))
    at = {}                                                   # joint -> body point on it
    for k, row in enumerate(W):
        if np.count_nonzero(row) == 1:
            at.setdefault(int(np.flatnonzero(row)[0]), k)
    eye, anchor = np.broadcast_to(np.eye(3), (T, 3, 3)), 0
    above = np.full(J, -1)                                    # nearest mapped ancestor
    for j, jt in enumerate(sk.joints[1:], start=1):
        above[j] = jt.parent if jt.parent in at else above[jt.parent]
    for j, jt in enumerate(sk.joints):
        base = G[:, jt.parent] if j else eye
        L = Gt[jt.parent].T @ Gt[j] if j else Gt[0]          # template local rotation
        if j:
            X[:, j] = X[:, jt.parent] + base @ jt.offset
            # where the rig's joint is off the body's (other bone lengths): aim from the
            # body's joint (or the body's place of an unmapped joint), so bones keep the
            # body's directions instead of bending to reach its absolute positions
            E[:, j] = X[:, j] - P[:, at[j]] if j in at else E[:, jt.parent]
        if plan[j] is None:
            G[:, j] = base @ L
            continue
        ks, direct = plan[j]
        rest = (W[ks] @ Xt - Xt[j]) @ Gt[j]                   # in the joint's frame
        if j:
            origin = X[:, j] - E[:, j]
            if j not in at and above[j] >= 0:
                origin = _unmapped_origin(origin, P, P[:, at[int(above[j])]],
                                          W[ks] @ Xt - Xt[above[j]], ks)
            G[:, j] = _fit(rest, P[:, ks] - origin[:, None], direct, base, L)
            continue
        i0 = int(np.argmax(ks == 0)) if 0 in ks else 0         # body point 0: the root
        keep = np.arange(len(ks)) != i0
        G[:, 0] = _fit(rest[keep] - rest[i0], P[:, ks[keep]] - P[:, ks[i0], None],
                       direct[keep] & direct[i0], base, L)
        X[:, 0] = P[:, ks[i0]] - G[:, 0] @ rest[i0]
        anchor = int(ks[i0])
    return G, X, anchor


def _drawn(sk: Skeleton, used: np.ndarray) -> np.ndarray:
    """(J,) the joints drawn as body: those the body points use (``used`` (J,)) and every
    joint below them (toe tips, fingers, end sites), but no helper above them (a root
    bone on the floor)."""
    drawn = np.asarray(used, dtype=bool).copy()
    for j, joint in enumerate(sk.joints):   # parents come before their children
        if joint.parent >= 0 and drawn[joint.parent]:
            drawn[j] = True
    return drawn


def _ground(P: np.ndarray, lowest: np.ndarray, used: np.ndarray, anchor: int) -> np.ndarray:
    """Shift (T, 3) (canonical frame) that puts the result's lowest drawn points
    (``lowest`` (T,) heights, toe tips included) on the floor of the given body points P
    (T, K, 3; the ``used`` (K,) ones) and scales the root's travel by the ratio of hip
    heights (the root point ``anchor`` above the floor)."""
    floor_p = np.percentile(P[:, used, 1].min(axis=1), 5)
    dy = floor_p - np.percentile(lowest, 5)
    height = float(np.median(P[:, anchor, 1] - floor_p))
    scale = (height + dy) / height if height > 1e-3 else 1.0
    shift = (scale - 1.0) * (P[:, anchor] - P[0, anchor])
    shift[:, 1] = dy
    return shift


def _euler_track(R: np.ndarray, axes: np.ndarray, start: np.ndarray) -> np.ndarray:
    """Angles (T, 3) of the Euler chain ``axes`` for R (T, 3, 3): of the two solutions
    ``(a, b, c)`` and ``(a + pi, pi - b, c + pi)``, each frame the one, shifted by 2 pi
    multiples, nearest the previous frame (``start`` (3,) before the first)."""
    a = matrix_to_chain(R, axes)
    alt = a + np.array([np.pi, 0.0, np.pi])
    alt[:, 1] = np.pi - a[:, 1]
    out, prev = np.empty_like(a), np.asarray(start, dtype=float)
    for t in range(len(a)):
        cands = [c + 2 * np.pi * np.round((prev - c) / (2 * np.pi)) for c in (a[t], alt[t])]
        prev = min(cands, key=lambda c: float(np.sum((c - prev) ** 2)))
        out[t] = prev
    return out


def _dofs(sk: Skeleton, G: np.ndarray, plan: list, tmpl: Motion
          ) -> tuple[np.ndarray, np.ndarray]:
    """World rotations (T, J, 3, 3) -> root rotation (T, 3) and joint angles (T, D)."""
    angles = np.repeat(tmpl.joint_angles, len(G), axis=0)
    for j, jt in enumerate(sk.joints[1:], start=1):
        if plan[j] is not None:
            L = np.swapaxes(G[:, jt.parent], -1, -2) @ G[:, j]
            cols = sk.dof_slice(j)
            angles[:, cols] = _euler_track(jt.pre.T @ L @ jt.post.T, jt.axes,
                                           tmpl.joint_angles[0, cols])
    root = sk.joints[0]
    own = root.pre @ chain(root.axes, tmpl.joint_angles[0, sk.dof_slice(0)]) @ root.post
    return _euler_track(G[:, 0] @ own.T, sk.root_axes, tmpl.root_rotation[0]), angles


def retarget(positions: np.ndarray, fps: float, rig: Motion, *, weights: np.ndarray,
             name: str = "retargeted", template_frame: int = 0, ground: bool = True
             ) -> Motion:
    """Joint angles on ``rig.skeleton`` (the same object: names, offsets, unit, DOF layout)
    whose body points ``weights @ joint positions`` follow ``positions`` as closely as the
    rig's bone lengths allow (see the module docstring for how, and what is exact).

    Args:
        positions: (T, K, 3) metres, canonical frame (Y up); point 0 is the body's root.
        fps: frames per second of ``positions``.
        rig: a motion read from the user's file: the skeleton, and the template frame's
            local rotations for the joints the body does not determine.
        weights: (K, J) body points as weights of the rig's joints, used rows summing to 1
            (``features.joint_map.kit21_weights(rig.skeleton)[1]``).
        template_frame: the frame of ``rig`` that gives the rest geometry.
        ground: stand the rig on the source's floor and scale its travel by the ratio of
            hip heights; False pins the root body point exactly where ``positions`` has it.

    Returns:
        Motion at ``fps`` with the rig's ``source_format`` and ``meta`` (minus
        ``PER_FILE_META``, plus ``meta["rig"]``), so that writers use the user's layout.

    Raises:
        MotionlangError: bad shapes or values; SkeletonError: a rig that cannot be aimed.
    """
    sk, P = rig.skeleton, np.asarray(positions, dtype=float)
    W = np.asarray(weights, dtype=float)
    if P.ndim != 3 or P.shape[2] != 3 or len(P) == 0 or not np.isfinite(P).all():
        raise MotionlangError(f"positions must be finite (T, K, 3) with T >= 1, got {P.shape}")
    if W.shape != (P.shape[1], len(sk)) or not np.isfinite(W).all():
        raise MotionlangError(f"weights must be finite ({P.shape[1]}, {len(sk)}), got {W.shape}")
    sums = W.sum(axis=1)[(W != 0).any(axis=1)]
    if not np.allclose(sums, 1.0, atol=1e-6):
        raise MotionlangError(f"every used row of weights must sum to 1, got {sums.round(4)}")
    if not 0 <= template_frame < rig.n_frames:
        raise MotionlangError(f"template frame {template_frame} outside 0..{rig.n_frames - 1}")
    plan = _plan(sk, W)
    tmpl = rig[template_frame:template_frame + 1]
    Gt, Xt = (a[0] for a in tmpl.global_transforms())
    G, X, anchor = _solve(P @ sk.world, W, sk, plan, Gt, Xt)
    translation = X[:, 0] - sk.joints[0].offset
    if ground:
        lowest = (X[:, _drawn(sk, (W != 0).any(axis=0))] @ sk.world.T)[..., 1].min(axis=1)
        translation += _ground(P, lowest, (W != 0).any(axis=1), anchor) @ sk.world
    root_rotation, angles = _dofs(sk, G, plan, tmpl)
    meta = {k: v for k, v in rig.meta.items() if k not in PER_FILE_META}
    meta["rig"] = str(rig.meta.get("path", rig.name))
    return Motion(sk, float(fps), translation, root_rotation, angles, name=name,
                  source_format=rig.source_format, meta=meta)
