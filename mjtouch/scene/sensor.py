"""Reading an ``mjtouch.skin`` instance's sensordata by block name.

The plugin writes, in this order, the output blocks its ``outputs`` attribute
enables: ``spikes`` (count per receptor in the step), ``stress`` (receptor
quantity, Pa, compressive positive), ``voltage`` (membrane potential over
threshold), ``force`` (normal, tangential x, y in N in the pad frame, the
solved approach in m, 1 when it exceeds the skin else 0), ``pressure``
(nx*nx taxel pressures, Pa), ``rate`` (smoothed rate per receptor, Hz),
``coverage`` (the share of MuJoCo's normal force on the pad geom that lands
on the skin's patch, 1 without contact, and that normal force in N;
:meth:`SkinLayout.coverage` reads it and warns); with ``shear="partial"``
``stick`` (nx*nx: 1 stick, 0 slip, -1 unloaded) and ``slip`` (stuck share of
the loaded cells, mu, shift x and y in m); ``shear`` (tangential tractions
along pad x then y, 2*nx*nx, Pa).
"""

from __future__ import annotations

import dataclasses
import json
import warnings

import mujoco
import numpy as np

import mjtouch.core  # noqa: F401  (first: a clear error when the compiled module is missing)
from mjtouch import _core, _loader

CLASSES = ("SA1", "RA", "PC")


class OffPatchWarning(UserWarning):
    """MuJoCo's contact on a skin's pad geom lands off the skin's patch."""


@dataclasses.dataclass(frozen=True)
class SkinLayout:
    instance: int
    sensor_id: int
    sensor_adr: int
    nx: int
    pitch_m: float
    blocks: dict[str, slice]  # relative to the sensor's first value
    classes: np.ndarray  # (nrec,) "SA1" / "RA" / "PC"
    positions_m: np.ndarray  # (nrec, 3): x, y in the pad frame, depth
    quantity: dict[str, str]  # class -> receptor quantity name
    substrate: str = ""  # the elastic skin (layered stack or half-space)
    kernel_build_s: float = 0.0  # kernel tables (+ FFT spectra) build time, s
    oversample: int = 1  # tactile evaluations per physics step (resolved `oversample`)

    @classmethod
    def from_model(cls, model: mujoco.MjModel, instance: int | str | None = None) -> SkinLayout:
        """Layout of one mjtouch.skin instance (by index or sensor name)."""
        inst = _find_instance(model, instance)
        info = json.loads(_core.describe_instance(_loader.loaded_path(), model._address, inst))
        if "error" in info:
            raise ValueError(info["error"])
        blocks = {b["name"]: slice(b["offset"], b["offset"] + b["size"]) for b in info["blocks"]}
        rec = info["receptors"]
        return cls(
            instance=inst,
            sensor_id=info["sensor_id"],
            sensor_adr=info["sensor_adr"],
            nx=info["nx"],
            pitch_m=info["pitch_m"],
            blocks=blocks,
            classes=np.array([r[0] for r in rec], dtype="<U3"),
            positions_m=np.array([r[1:] for r in rec], dtype=float).reshape(-1, 3),
            quantity=dict(zip(CLASSES, info["quantity"])),
            substrate=info.get("substrate", ""),
            kernel_build_s=float(info.get("kernel_build_s", 0.0)),
            oversample=int(info.get("oversample", 1)),
        )

    @property
    def size(self) -> int:
        return max((s.stop for s in self.blocks.values()), default=0)

    def block(self, sensordata: np.ndarray, name: str) -> np.ndarray:
        """View of block `name` in sensordata (last axis = model.nsensordata)."""
        if name not in self.blocks:
            raise KeyError(
                f"output block {name!r} is not enabled; enabled: {sorted(self.blocks)} "
                "(set the plugin's `outputs` attribute)"
            )
        s = self.blocks[name]
        return sensordata[..., self.sensor_adr + s.start : self.sensor_adr + s.stop]

    def coverage(self, sensordata: np.ndarray) -> np.ndarray:
        """The share of MuJoCo's normal force on the pad geom that the skin's
        patch carries (the ``coverage`` block's first value; 1 without
        contact), for sensordata of any leading shape; an OffPatchWarning
        when some of it lands off the patch (past the grid, or on the
        geom's side or back), where the skin feels nothing."""
        block = self.block(sensordata, "coverage")
        share, normal_n = block[..., 0], block[..., 1]
        off = (share < 1.0 - 1e-6) & (normal_n > 0)
        if np.any(off):
            k = np.argmin(np.where(off, share, np.inf))
            warnings.warn(
                f"skin sensor {self.sensor_id}: contact off the skin's patch: it carries "
                f"{float(np.ravel(share)[k]):.3g} of MuJoCo's {float(np.ravel(normal_n)[k]):.3g} "
                f"N normal force on its pad geom (worst of {int(np.sum(off))} off-patch "
                "rows); widen the grid (nx, pitch) or turn the skin (facing)",
                OffPatchWarning,
                stacklevel=2,
            )
        return share

    def image(self, sensordata: np.ndarray, name: str) -> np.ndarray:
        """A taxel block as images: ``pressure`` and ``stick`` (..., nx, nx),
        ``shear`` (..., 2, nx, nx) with x then y; row j is pad y."""
        if name not in ("pressure", "stick", "shear"):
            raise ValueError(f"block {name!r} is not a taxel image; valid: pressure stick shear")
        values = self.block(sensordata, name)
        shape = (2, self.nx, self.nx) if name == "shear" else (self.nx, self.nx)
        return values.reshape(values.shape[:-1] + shape)

    def last_evaluation(self, data: mujoco.MjData) -> dict:
        """Diagnostics of this instance's last evaluation in ``data`` (the
        plugin's scratch, not its state): the stress path taken, the
        ``elastic`` solve's iterations, convergence, last relative pressure
        change, contact cells and FFT size, and the cells with traction."""
        return _core.last_evaluation(_loader.loaded_path(), data._address, self.instance)

    def mask(self, cls_name: str) -> np.ndarray:
        if cls_name not in CLASSES:
            raise ValueError(f"unknown receptor class {cls_name!r}; valid: {CLASSES}")
        return self.classes == cls_name


def _find_instance(model: mujoco.MjModel, instance: int | str | None) -> int:
    plugin_sensors = [
        i for i in range(model.nsensor) if model.sensor_type[i] == mujoco.mjtSensor.mjSENS_PLUGIN
    ]
    instances = [int(model.sensor_plugin[i]) for i in plugin_sensors]
    if instance is None:
        if not instances:
            raise ValueError("model has no mjtouch.skin sensor")
        return instances[0]
    if isinstance(instance, str):
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, instance)
        if sid < 0 or sid not in plugin_sensors:
            raise ValueError(f"no mjtouch.skin sensor named {instance!r}")
        return int(model.sensor_plugin[sid])
    if instance not in instances:
        raise ValueError(f"plugin instance {instance} is not a sensor plugin; valid: {instances}")
    return int(instance)
