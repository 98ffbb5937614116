"""A faster drop-in for robosuite's `check_contact` on one environment instance.

LIBERO's goal predicates (`On`, `In`, …) ask robosuite whether two objects touch, and robosuite answers
by walking the whole contact list in Python, translating every geom id to its name, for every
question. Evaluating the goals of all tasks of a scene at every step asks dozens of such questions
per step. `ContactIndex` reads the contact list once per simulator state and answers each question
with array lookups. Its answers are those of robosuite's method, which a test checks on real rollouts.
"""

from __future__ import annotations

import mujoco
import numpy as np
from robosuite.models.base import MujocoModel


class ContactIndex:
    """Callable like `MujocoEnv.check_contact(geoms_1, geoms_2=None)`, for the env it is installed on."""

    def __init__(self, env):
        self.env = env
        self._state_key: tuple | None = None
        self._geom1 = self._geom2 = np.zeros(0, dtype=np.int64)
        self._ids: dict[tuple[str, ...], np.ndarray] = {}

    @classmethod
    def install(cls, env) -> None:
        """Answer `env.check_contact` (and so LIBERO's predicates) through a new index."""
        env.check_contact = cls(env)

    def _refresh(self) -> None:
        data = self.env.sim.data._data
        key = (id(data), data.time, data.qpos.tobytes())
        if key != self._state_key:
            contacts = data.contact
            self._geom1 = np.array(contacts.geom1[: data.ncon])
            self._geom2 = np.array(contacts.geom2[: data.ncon])
            self._state_key = key
            if len(self._ids) > 4096:
                self._ids.clear()

    def _geom_ids(self, geoms) -> np.ndarray:
        if type(geoms) is str:
            names = (geoms,)
        elif isinstance(geoms, MujocoModel):
            names = tuple(geoms.contact_geoms)
        else:
            names = tuple(geoms)
        model = self.env.sim.model._model
        key = (id(model), *names)
        if key not in self._ids:
            ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, n) for n in names if isinstance(n, str)]
            self._ids[key] = np.array([i for i in ids if i >= 0], dtype=np.int64)
        return self._ids[key]

    def __call__(self, geoms_1, geoms_2=None) -> bool:
        self._refresh()
        first = self._geom_ids(geoms_1)
        in_first_1 = np.isin(self._geom1, first)
        in_first_2 = np.isin(self._geom2, first)
        if geoms_2 is None:
            return bool((in_first_1 | in_first_2).any())
        second = self._geom_ids(geoms_2)
        return bool(((in_first_1 & np.isin(self._geom2, second)) | (np.isin(self._geom1, second) & in_first_2)).any())

    def partners(self, geoms) -> np.ndarray:
        """The ids of the geoms touching any of `geoms` (a name, names or a model) in the current state."""
        self._refresh()
        first = self._geom_ids(geoms)
        return np.concatenate([self._geom2[np.isin(self._geom1, first)], self._geom1[np.isin(self._geom2, first)]])
