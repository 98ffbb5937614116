"""Privileged state: the simulator facts a policy that `sees_state` may read, extracted from a `TaskEnv`.

The result is a `PrivilegedState` (`langgap.sim.privileged_schema`, which lists its keys): a flat
mapping of numpy arrays, so it crosses a process or network boundary unchanged and a scripted
policy can also be served remotely.

Static parts are computed once per simulator model and cached on the environment; a step's
extraction is vectorised numpy (well under a millisecond).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from langgap.sim.privileged_schema import PrivilegedState

_ROBOT_PREFIXES = ("robot0_", "gripper0_", "mount0_")
_GRIPPER_PREFIX = "gripper0_"
# LIBERO predicate name -> fixture method deciding it from a joint's qpos.
_ARTICULATION_TESTS = {"open": "is_open", "close": "is_close", "on": "turn_on", "off": "turn_off"}
_INTERVAL_SAMPLES = 421
# Parts reaching within this distance of the outermost point of a moving part form its handle.
_HANDLE_TOLERANCE = 0.01


@dataclass
class _Articulation:
    joint: int
    qpos_adr: int
    slide: bool
    limits: np.ndarray
    body: int  # the body the joint moves
    geoms: np.ndarray  # collision geoms of that body and its subtree
    shape: np.ndarray  # those geoms as boxes in the body's frame
    intervals: dict[str, np.ndarray] = field(default_factory=dict)
    handle: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))  # geoms forming its handle


@dataclass
class _Layout:
    model_id: int
    entity_roots: dict[str, int]
    entity_geoms: dict[str, np.ndarray]
    shapes: dict[str, np.ndarray]
    parts: dict[str, np.ndarray]
    geom_entity: np.ndarray  # geom -> entity index, -1 robot, -2 other (table, walls)
    entity_names: list[str]
    movable: dict[str, np.ndarray]
    gripper_geom: np.ndarray  # bool per geom
    sites: dict[str, tuple[int, np.ndarray]]
    joints: dict[str, int]
    articulations: dict[str, _Articulation]
    robot_base: int
    box_geoms: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    box_spans: dict[str, tuple[int, int]] = field(default_factory=dict)  # name -> slice of box_geoms


def _subtree_bodies(model, root: int) -> np.ndarray:
    bodies = [root]
    for body in range(root + 1, model.nbody):
        parent = model.body_parentid[body]
        if parent in bodies:
            bodies.append(body)
    return np.array(bodies)


def _collision_geoms(model, bodies) -> np.ndarray:
    collides = (model.geom_contype != 0) | (model.geom_conaffinity != 0)
    return np.flatnonzero(np.isin(model.geom_bodyid, bodies) & collides)


def _geom_boxes(model, data, geoms: np.ndarray) -> np.ndarray:
    """World-frame AABBs (n, 6) of `geoms` from their model-frame AABBs and current poses."""
    rot = data.geom_xmat[geoms].reshape(-1, 3, 3)
    centre = data.geom_xpos[geoms] + np.einsum("nij,nj->ni", rot, model.geom_aabb[geoms, :3])
    half = np.einsum("nij,nj->ni", np.abs(rot), model.geom_aabb[geoms, 3:])
    return np.concatenate([centre - half, centre + half], axis=1)


def _union(boxes: np.ndarray) -> np.ndarray:
    return np.concatenate([boxes[:, :3].min(axis=0), boxes[:, 3:].max(axis=0)])


def _interval(fixture, method: str, limits: np.ndarray) -> np.ndarray | None:
    """The qpos interval (within `limits`) where `fixture.<method>(qpos)` holds, or None.

    Found on a grid, then each inner boundary is refined by bisection (LIBERO's tests are strict
    inequalities, some intervals are only millimetres wide).
    """
    test = getattr(fixture, method, None)
    if test is None:
        return None
    grid = np.linspace(limits[0], limits[1], _INTERVAL_SAMPLES)
    try:
        holds = np.array([bool(test(q)) for q in grid])
    except NotImplementedError:
        return None
    if not holds.any():
        return None
    first, last = np.flatnonzero(holds)[[0, -1]]
    lo = grid[first] if first == 0 else _boundary(test, grid[first - 1], grid[first])
    hi = grid[last] if last == len(grid) - 1 else _boundary(test, grid[last + 1], grid[last])
    return np.array([lo, hi])


def _boundary(test, outside: float, inside: float) -> float:
    """The point nearest `outside` where `test` still holds, between a failing and a holding qpos."""
    for _ in range(30):
        middle = (outside + inside) / 2.0
        if test(middle):
            inside = middle
        else:
            outside = middle
    return inside


def _handle_geoms(model, data, geoms: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """The geoms reaching (nearly) as far along `direction` as the farthest one (exact for rotated boxes)."""
    rot = data.geom_xmat[geoms].reshape(-1, 3, 3)
    centre = data.geom_xpos[geoms] + np.einsum("nij,nj->ni", rot, model.geom_aabb[geoms, :3])
    local_direction = np.einsum("nji,j->ni", rot, direction)
    reach = centre @ direction + np.sum(np.abs(local_direction) * model.geom_aabb[geoms, 3:], axis=1)
    return geoms[reach >= reach.max() - _HANDLE_TOLERANCE]


def _articulation(model, fixture, joint_name: str, data) -> _Articulation:
    joint = model.joint_name2id(joint_name)
    raw = model._model
    slide = int(raw.jnt_type[joint]) == 2  # mjJNT_SLIDE
    limits = np.array(raw.jnt_range[joint], dtype=np.float64)
    body = int(raw.jnt_bodyid[joint])
    geoms = _collision_geoms(raw, _subtree_bodies(raw, body))
    art = _Articulation(
        joint=joint,
        qpos_adr=int(raw.jnt_qposadr[joint]),
        slide=slide,
        limits=limits,
        body=body,
        geoms=geoms,
        shape=_local_boxes(_local_parts(data, raw, body, geoms)),
    )
    for key, method in _ARTICULATION_TESTS.items():
        interval = _interval(fixture, method, limits)
        if interval is not None:
            art.intervals[key] = interval
    if geoms.size:
        # Rigidly attached to the moving body: which geoms form the handle never changes.
        art.handle = _handle_geoms(raw, data, geoms, _opening_direction(art, data))
    return art


def _layout(env) -> _Layout:
    import mujoco  # here, not above: reading demonstrations (`langgap.demos`) imports this module without simulating

    sim = env.sim
    model = sim.model
    raw = model._model
    cached = getattr(env, "_privileged_layout", None)
    if cached is not None and cached.model_id == id(raw):
        return cached
    inner = env.robosuite_env
    # The static parts are read from the model's reference pose, never from the current state: computed
    # from whichever state came first, they would differ in the last bits from one episode order to the
    # next, and so would every action an oracle derives from them.
    data = mujoco.MjData(raw)
    mujoco.mj_kinematics(raw, data)
    entities = {**inner.objects_dict, **inner.fixtures_dict}
    names = list(entities)
    geom_entity = np.full(raw.ngeom, -2, dtype=np.int64)
    body_names = [model.body_id2name(b) or "" for b in range(raw.nbody)]
    robot_bodies = [b for b, n in enumerate(body_names) if n.startswith(_ROBOT_PREFIXES)]
    geom_entity[np.isin(raw.geom_bodyid, robot_bodies)] = -1
    gripper_bodies = [b for b, n in enumerate(body_names) if n.startswith(_GRIPPER_PREFIX)]
    gripper_geom = np.isin(raw.geom_bodyid, gripper_bodies)
    roots, geoms_of, shapes, parts = {}, {}, {}, {}
    articulations: dict[str, _Articulation] = {}
    for index, (name, obj) in enumerate(entities.items()):
        root = model.body_name2id(obj.root_body)
        bodies = _subtree_bodies(raw, root)
        geoms = _collision_geoms(raw, bodies)
        roots[name], geoms_of[name] = root, geoms
        geom_entity[geoms] = index
        moved = set()
        joint_names = [j for j in getattr(obj, "joints", []) or [] if j in model.joint_names]
        if name in inner.fixtures_dict:
            for joint_name in joint_names:
                moved.update(_subtree_bodies(raw, int(raw.jnt_bodyid[model.joint_name2id(joint_name)])).tolist())
            if joint_names:
                articulations[name] = _articulation(model, obj, joint_names[0], data)
        static = np.array([g for g in geoms if raw.geom_bodyid[g] not in moved], dtype=np.int64)
        parts[name] = _local_parts(data, raw, root, static)
        shapes[name] = _local_boxes(parts[name])
    sites = {}
    for site_name, site in inner.object_sites_dict.items():
        size = np.asarray(site.size, dtype=np.float64)
        sites[site_name] = (model.site_name2id(site_name), size)
        joint_names = [j for j in site.joints or [] if j in model.joint_names]
        parent = inner.fixtures_dict.get(site.parent_name)
        if joint_names and parent is not None:
            articulations[site_name] = _articulation(model, parent, joint_names[0], data)
    joints = {
        j: raw.jnt_qposadr[model.joint_name2id(j)]
        for j in model.joint_names
        if j and any(j.startswith(f) for f in inner.fixtures_dict)
    }
    layout = _Layout(
        model_id=id(raw),
        entity_roots=roots,
        entity_geoms=geoms_of,
        shapes=shapes,
        parts=parts,
        geom_entity=geom_entity,
        entity_names=names,
        movable={name: np.array([1.0 if name in inner.objects_dict else 0.0]) for name in names},
        gripper_geom=gripper_geom,
        sites=sites,
        joints=joints,
        articulations=articulations,
        robot_base=model.body_name2id(inner.robots[0].robot_model.root_body),
    )
    # Every world box a step reports, computed in one vectorised pass over these geoms.
    groups = {f"bbox/{n}": g for n, g in geoms_of.items() if g.size}
    for name, art in articulations.items():
        if art.geoms.size:
            groups[f"art/{name}/bbox"] = art.geoms
            groups[f"art/{name}/handle"] = art.handle
    start = 0
    for key, geoms in groups.items():
        layout.box_spans[key] = (start, start + len(geoms))
        start += len(geoms)
    layout.box_geoms = np.concatenate(list(groups.values())) if groups else np.zeros(0, dtype=np.int64)
    env._privileged_layout = layout
    return layout


def _local_parts(data, raw, root: int, geoms: np.ndarray) -> np.ndarray:
    """Oriented boxes of `geoms` in the frame of body `root` (valid while the body is rigid, i.e.
    always): centre (3), half-sizes along the box's own axes (3), rotation to the body's frame (9)."""
    if geoms.size == 0:
        return np.zeros((0, 15))
    body_rot = data.xmat[root].reshape(3, 3)
    rot = np.einsum("ji,njk->nik", body_rot, data.geom_xmat[geoms].reshape(-1, 3, 3))
    world_centre = data.geom_xpos[geoms] + np.einsum(
        "nij,nj->ni", data.geom_xmat[geoms].reshape(-1, 3, 3), raw.geom_aabb[geoms, :3]
    )
    centre = (world_centre - data.xpos[root]) @ body_rot
    return np.concatenate([centre, raw.geom_aabb[geoms, 3:], rot.reshape(-1, 9)], axis=1)


def _local_boxes(parts: np.ndarray) -> np.ndarray:
    """The axis-aligned bounds (min xyz, max xyz) in the body's frame of each oriented box of `parts`."""
    rot = parts[:, 6:].reshape(-1, 3, 3)
    half = np.einsum("nij,nj->ni", np.abs(rot), parts[:, 3:6])
    return np.concatenate([parts[:, :3] - half, parts[:, :3] + half], axis=1)


def _contacts(layout: _Layout, data) -> dict[str, np.ndarray]:
    count = data.ncon
    touching = {name: np.zeros(2) for name in layout.entity_names}
    if count == 0:
        return touching
    g1 = data.contact.geom1[:count]
    g2 = data.contact.geom2[:count]
    e1, e2 = layout.geom_entity[g1], layout.geom_entity[g2]
    for a, b, other_geom in ((e1, e2, g2), (e2, e1, g1)):
        for index in np.unique(a[a >= 0]):
            mine = a == index
            partner = b[mine]
            name = layout.entity_names[index]
            touching[name][0] = max(touching[name][0], float(np.any((partner != index) & (partner != -1))))
            touching[name][1] = max(touching[name][1], float(np.any(layout.gripper_geom[other_geom[mine]])))
    return touching


def privileged_state(env) -> PrivilegedState:
    """The privileged state of a `TaskEnv` at its current simulator state."""
    layout = _layout(env)
    sim = env.sim
    model = sim.model._model
    data = sim.data._data
    robot = env.robosuite_env.robots[0]
    out: dict[str, np.ndarray] = {
        "eef_pos": np.array(data.site_xpos[robot.eef_site_id]),
        "eef_mat": np.array(data.site_xmat[robot.eef_site_id]).reshape(3, 3),
        "gripper_qpos": np.array([data.qpos[i] for i in robot._ref_gripper_joint_pos_indexes]),
        "base_pos": np.array(data.xpos[layout.robot_base]),
    }
    boxes = _geom_boxes(model, data, layout.box_geoms)
    for key, (start, end) in layout.box_spans.items():
        union = _union(boxes[start:end])
        out[key] = union.reshape(2, 3).mean(axis=0) if key.endswith("/handle") else union
    for name, root in layout.entity_roots.items():
        out[f"body/{name}"] = np.concatenate([data.xpos[root], data.xquat[root]])
        out[f"shape/{name}"] = layout.shapes[name]
        out[f"parts/{name}"] = layout.parts[name]
        out[f"movable/{name}"] = layout.movable[name]
    for name, touch in _contacts(layout, data).items():
        out[f"contact/{name}"] = touch
    for name, (site_id, size) in layout.sites.items():
        out[f"site/{name}"] = np.array(data.site_xpos[site_id])
        out[f"site_mat/{name}"] = np.array(data.site_xmat[site_id]).reshape(3, 3)
        out[f"site_size/{name}"] = size
    for name, adr in layout.joints.items():
        out[f"joint/{name}"] = np.array([data.qpos[adr]])
    for name, art in layout.articulations.items():
        prefix = f"art/{name}/"
        out[prefix + "qpos"] = np.array([data.qpos[art.qpos_adr]])
        out[prefix + "anchor"] = np.array(data.xanchor[art.joint])
        out[prefix + "axis"] = np.array(data.xaxis[art.joint])
        out[prefix + "slide"] = np.array([1.0 if art.slide else 0.0])
        out[prefix + "limits"] = art.limits
        out.update({prefix + key: interval for key, interval in art.intervals.items()})
        out[prefix + "body"] = np.concatenate([data.xpos[art.body], data.xquat[art.body]])
        out[prefix + "shape"] = art.shape
    return PrivilegedState(out)


def _opening_direction(art: _Articulation, data) -> np.ndarray:
    """World direction the moving part travels (slide) or faces (hinge) when opening."""
    axis = np.array(data.xaxis[art.joint])
    opened, closed = art.intervals.get("open"), art.intervals.get("close")
    sign = 1.0 if opened is None or closed is None else float(np.sign(opened.mean() - closed.mean()) or 1.0)
    # A hinge's handle (a knob's grip, a door's edge) is taken as its highest part.
    return sign * axis if art.slide else np.array([0.0, 0.0, 1.0])
