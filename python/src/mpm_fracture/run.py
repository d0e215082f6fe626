"""Reading a run: the folder ``fracture run SCENE --out DIR`` writes, or a job's results
downloaded from the service (:meth:`mpm_fracture.Client.run`).

A run folder holds (the project's ``docs/run-output.md`` and
``docs/run-output-extensions.md``):

* ``summary.json``: how the run ended, its size and speed, and (newer servers) per-tip
  summaries (``tips``) and comparisons with reference values (``references``);
* ``crack_tips.csv``: one row per crack tip per history sample;
* ``energy.csv``: one row per history sample;
* ``fields.mcap``: the field snapshots (and the histories again).

Units are SI throughout; every column is listed in :attr:`Run.crack_tips` and
:attr:`Run.energy`.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Dict, Iterable, Iterator, List, Optional, Union

import numpy as np
import pandas as pd

from .codec import Snapshot
from .errors import RunFormatError
from .mcapfile import iter_snapshots, read_mcap

if TYPE_CHECKING:  # pragma: no cover
    from .client import Client

__all__ = [
    "Run",
    "read_crack_tips_csv",
    "read_energy_csv",
    "crack_tips_frame",
    "energy_frame",
    "CRACK_TIPS_UNITS",
    "ENERGY_UNITS",
    "TIPS_UNITS",
]

PathLike = Union[str, "os.PathLike[str]"]

#: Unit of every ``crack_tips.csv`` column (``1``: a number without unit; ``-``: an index
#: or a flag).
CRACK_TIPS_UNITS: Dict[str, str] = {
    "time": "s",
    "crack": "-",
    "tip": "-",
    "x": "m",
    "y": "m",
    "length": "m",
    "speed": "m/s",
    "j1": "J/m²",
    "j2": "J/m²",
    "k1": "Pa·√m",
    "k2": "Pa·√m",
    "growing": "-",
    "j1_half": "J/m²",
    "j2_half": "J/m²",
    "j1_double": "J/m²",
    "j2_double": "J/m²",
    "k1_cod": "Pa·√m",
    "k2_cod": "Pa·√m",
    "zone_x": "m",
    "zone_y": "m",
    "connected_x": "m",
    "connected_y": "m",
    "zone_connected_x": "m",
    "zone_connected_y": "m",
}

#: Unit of every ``energy.csv`` column: energies in J for the scene's thickness.
ENERGY_UNITS: Dict[str, str] = {
    "time": "s",
    "kinetic": "J",
    "strain": "J",
    "external_work": "J",
    "dissipated": "J",
    "total_error": "J",
    "fracture": "J",
}

#: Unit of every column of :attr:`Run.tips` (``summary.json``'s ``tips``).
TIPS_UNITS: Dict[str, str] = {
    "crack": "-",
    "tip": "-",
    "samples": "-",
    "x": "m",
    "y": "m",
    "initiation_time": "s",
    "growth": "m",
    "j1_final": "J/m²",
    "j1_peak": "J/m²",
    "k1_final": "Pa·√m",
    "k1_peak": "Pa·√m",
    "k2_final": "Pa·√m",
    "k2_peak": "Pa·√m",
    "mean_speed": "m/s",
    "peak_speed": "m/s",
    "speed_window": "s",
}

_INT_COLUMNS = ("crack", "tip")


def _tidy_crack_tips(df: pd.DataFrame) -> pd.DataFrame:
    for c in _INT_COLUMNS:
        if c in df.columns:
            df[c] = pd.to_numeric(df[c]).astype("int64")
    if "growing" in df.columns:
        g = df["growing"]
        if g.dtype != bool:
            g = pd.to_numeric(g.map(lambda v: 1 if v is True else (0 if v is False else v)))
        df["growing"] = g.astype(bool)
    for c in df.columns:
        if c not in _INT_COLUMNS and c != "growing":
            df[c] = pd.to_numeric(df[c], errors="coerce").astype("float64")
    return df


def _tidy_floats(df: pd.DataFrame) -> pd.DataFrame:
    for c in df.columns:
        df[c] = pd.to_numeric(df[c], errors="coerce").astype("float64")
    return df


def read_crack_tips_csv(path_or_buffer: Any) -> pd.DataFrame:
    """Read a ``crack_tips.csv`` (a file path, or a file-like object such as
    ``io.StringIO``) into a DataFrame with the columns of :attr:`Run.crack_tips`.

    ``NaN``, ``inf`` and ``-inf`` read as such; ``crack`` and ``tip`` are integers,
    ``growing`` a bool, every other column float64.
    """
    df = pd.read_csv(path_or_buffer, na_values=["NaN", "nan"], keep_default_na=True)
    return _tidy_crack_tips(df)


def read_energy_csv(path_or_buffer: Any) -> pd.DataFrame:
    """Read an ``energy.csv`` into a DataFrame with the columns of :attr:`Run.energy`."""
    df = pd.read_csv(path_or_buffer, na_values=["NaN", "nan"], keep_default_na=True)
    return _tidy_floats(df)


def crack_tips_frame(rows: List[Dict[str, Any]]) -> pd.DataFrame:
    """Crack-tip rows as the API's JSON (or the MCAP's ``/crack_tips``) gives them
    (``null`` for NaN) as a DataFrame with the columns of :attr:`Run.crack_tips`."""
    if not rows:
        return pd.DataFrame({c: pd.Series(dtype="float64") for c in CRACK_TIPS_UNITS}).pipe(
            _tidy_crack_tips
        )
    return _tidy_crack_tips(pd.DataFrame.from_records(rows))


def energy_frame(rows: List[Dict[str, Any]]) -> pd.DataFrame:
    """Energy rows as the API's JSON gives them as a DataFrame (columns of
    :attr:`Run.energy`)."""
    if not rows:
        return pd.DataFrame({c: pd.Series(dtype="float64") for c in ENERGY_UNITS})
    return _tidy_floats(pd.DataFrame.from_records(rows))


class Run:
    """A run's results: summary, histories and field snapshots.

    Open a folder written by ``fracture run SCENE.json --out DIR`` with :meth:`open`, or a
    service job with :meth:`from_job` / :meth:`mpm_fracture.Client.run` (which download
    its files into a folder first). Files are read when first used and cached.

    Example::

        run = Run.open("out/center-crack")
        print(run.summary["status"], run.summary["steps"])
        tips = run.crack_tips                        # DataFrame, SI units
        late = tips[tips.time > 0.8 * tips.time.max()]
        print(late.groupby("tip").k1.mean())         # Pa·√m
        for snap in run.snapshots(["syy"]):
            print(snap.time, np.nanmax(snap["syy"]))  # s, Pa
    """

    def __init__(self, path: PathLike, job: Optional[Dict[str, Any]] = None) -> None:
        """Use :meth:`open` (a run folder) or :meth:`from_job` instead."""
        self.path = Path(path)
        #: The job this run came from (``GET /api/v1/jobs/{id}``), or ``None`` for a local
        #: run folder.
        self.job: Optional[Dict[str, Any]] = job
        self._summary: Optional[Dict[str, Any]] = None
        self._crack_tips: Optional[pd.DataFrame] = None
        self._energy: Optional[pd.DataFrame] = None

    # ----------------------------------------------------------------- constructors

    @classmethod
    def open(cls, path: PathLike) -> "Run":
        """Open a run folder (or its ``summary.json``, or its ``fields.mcap``).

        Raises:
            RunFormatError: the folder does not exist or holds none of the run files.
        """
        p = Path(path)
        if p.is_file():
            p = p.parent
        if not p.is_dir():
            raise RunFormatError(f"no run folder at {p}")
        names = ("summary.json", "crack_tips.csv", "energy.csv", "fields.mcap")
        if not any((p / n).exists() for n in names):
            raise RunFormatError(
                f"{p} is not a run folder: it has none of {', '.join(names)} "
                "(`fracture run SCENE.json --out DIR` writes them)"
            )
        return cls(p)

    @classmethod
    def from_job(
        cls,
        client: "Client",
        job_id: str,
        folder: Optional[PathLike] = None,
        snapshots: bool = True,
    ) -> "Run":
        """Download a service job's results into ``folder`` and open them.

        Same as :meth:`mpm_fracture.Client.run`: ``summary.json`` (from the job),
        ``crack_tips.csv``, ``energy.csv`` and (if ``snapshots``, and the job has any)
        ``fields.mcap``. ``folder`` defaults to a new temporary folder.
        """
        return client.run(job_id, folder=folder, snapshots=snapshots)

    # ----------------------------------------------------------------- summary

    @property
    def summary(self) -> Dict[str, Any]:
        """``summary.json`` as a dict: ``status`` (``completed``, ``failed``,
        ``cancelled``), ``message``, ``steps``, ``time_step`` (s), ``sim_time`` (s),
        ``particles``, ``grid_nodes``, ``active_nodes_mean``, ``wall_seconds`` (s),
        ``particle_steps_per_second``, ``threads``, ``scene_hash``, ``solver_version``,
        and where present ``fracture`` (J, m²), ``provenance``, ``tips``, ``references``.

        Empty dict when the run has no summary yet (a job still running).
        """
        if self._summary is None:
            f = self.path / "summary.json"
            if f.exists():
                with open(f, encoding="utf-8") as fh:
                    self._summary = json.load(fh)
            elif self.job is not None and self.job.get("summary"):
                self._summary = dict(self.job["summary"])
            else:
                self._summary = {}
        return self._summary

    @property
    def status(self) -> Optional[str]:
        """``summary["status"]`` (``completed``, ``failed``, ``cancelled``), or ``None``
        without a summary."""
        s = self.summary.get("status")
        return str(s) if s is not None else None

    @property
    def tips(self) -> pd.DataFrame:
        """Per-tip summary from ``summary["tips"]`` (empty DataFrame when the summary
        has none, e.g. written by an older solver). One row per crack tip:

        ==================  ======  ===============================================
        column              unit    meaning
        ==================  ======  ===============================================
        ``crack``           --      index into ``scene.cracks`` (interfaces after)
        ``tip``             --      0 start of the polyline, 1 its end
        ``samples``         --      history samples of the tip
        ``x``, ``y``        m       tip position at the end
        ``initiation_time`` s       when the tip started to grow (NaN/None: never)
        ``growth``          m       how far the crack grew at this tip
        ``j1_final``        J/m²    J1 at the last sample
        ``j1_peak``         J/m²    peak J1
        ``k1_final``        Pa·√m   K_I at the last sample
        ``k1_peak``         Pa·√m   peak K_I
        ``k2_final``        Pa·√m   K_II at the last sample
        ``k2_peak``         Pa·√m   peak K_II
        ``mean_speed``      m/s     mean tip speed
        ``peak_speed``      m/s     peak tip speed
        ``speed_window``    s       the moving-box window of the speeds
        ==================  ======  ===============================================

        Columns the summary adds later appear too; ``null`` reads as NaN.
        """
        rows = self.summary.get("tips") or []
        if not rows:
            return pd.DataFrame({c: pd.Series(dtype="float64") for c in TIPS_UNITS})
        df = pd.DataFrame.from_records(rows)
        for c in df.columns:
            if c in ("crack", "tip", "samples"):
                df[c] = pd.to_numeric(df[c], errors="coerce").astype("Int64")
            else:
                conv = pd.to_numeric(df[c], errors="coerce")
                if conv.notna().sum() == df[c].notna().sum():
                    df[c] = conv.astype("float64")
        return df

    @property
    def references(self) -> pd.DataFrame:
        """Comparisons with reference values from ``summary["references"]`` (empty
        DataFrame when absent): ``quantity``, ``value`` (the reference, in the quantity's
        SI unit), ``measured`` (the run's value), ``relative_error`` ((measured − value) /
        value), ``source`` (where the reference comes from), and any further fields."""
        rows = self.summary.get("references") or []
        if not rows:
            return pd.DataFrame(
                {c: pd.Series(dtype="object") for c in ("quantity", "value", "measured", "relative_error", "source")}
            )
        return pd.DataFrame.from_records(rows)

    # ----------------------------------------------------------------- histories

    @property
    def crack_tips(self) -> pd.DataFrame:
        """The crack-tip history (``crack_tips.csv``), one row per tip per history sample.

        ================  ======  =====================================================
        column            unit    meaning
        ================  ======  =====================================================
        ``time``          s       simulated time
        ``crack``         --      index into ``scene.cracks`` (interfaces follow)
        ``tip``           --      0 start of the crack's polyline, 1 its end
        ``x``, ``y``      m       tip position
        ``length``        m       crack length along its path
        ``speed``         m/s     tip speed (moving-box average, ``output.speed_window``)
        ``j1``, ``j2``    J/m²    J-integral in the tip frame (1 ahead, 2 normal, to the
                                  crack's left)
        ``k1``, ``k2``    Pa·√m   stress intensity factors K_I, K_II
        ``growing``       bool    whether the tip advanced in this sample's step
        ``j1_half`` …     J/m²    ``j1_half``, ``j2_half``, ``j1_double``, ``j2_double``:
                                  J at half and twice the J radius (path independence)
        ``k1_cod``,       Pa·√m   K by the crack-opening ratio, for comparison
        ``k2_cod``
        ``zone_x``,       m       a cohesive interface's process-zone front (NaN for
        ``zone_y``                crack tips)
        ``connected_x``,  m       its failure front and softened region's end connected
        ``connected_y``,          to its first point (``zone_connected_x``,
        ``zone_…``                ``zone_connected_y``); apart from ``x`` / ``zone_x``
                                  when a point ahead failed or softened first
        ================  ======  =====================================================

        NaN where a number is not defined (a J ring that leaves the material, K of a tip at
        or above c_R). Read from ``crack_tips.csv``, or from ``fields.mcap`` when the
        folder has no CSV. The units are also in :data:`CRACK_TIPS_UNITS`.
        """
        if self._crack_tips is None:
            f = self.path / "crack_tips.csv"
            if f.exists():
                self._crack_tips = read_crack_tips_csv(f)
            elif (self.path / "fields.mcap").exists():
                self._crack_tips = crack_tips_frame(
                    read_mcap(self.path / "fields.mcap", snapshots=False).crack_tips
                )
            else:
                raise RunFormatError(f"{self.path} has no crack_tips.csv (nor fields.mcap)")
        return self._crack_tips

    @property
    def energy(self) -> pd.DataFrame:
        """The energy history (``energy.csv``), one row per history sample. Energies are in
        J for the scene's thickness (per metre of thickness when ``thickness`` is 1).

        =================  ====  ===================================================
        column             unit  meaning
        =================  ====  ===================================================
        ``time``           s     simulated time
        ``kinetic``        J     Σ ½ m |v|²
        ``strain``         J     Σ V W (strain energy)
        ``external_work``  J     work done on the body by boundary conditions and loads
        ``dissipated``     J     removed by friction, damping and crack growth
        ``total_error``    J     kinetic + strain + dissipated − external_work − initial
        ``fracture``       J     the part of ``dissipated`` spent on new crack surface
        =================  ====  ===================================================

        Read from ``energy.csv``, or from ``fields.mcap`` when the folder has no CSV.
        """
        if self._energy is None:
            f = self.path / "energy.csv"
            if f.exists():
                self._energy = read_energy_csv(f)
            elif (self.path / "fields.mcap").exists():
                self._energy = energy_frame(
                    read_mcap(self.path / "fields.mcap", snapshots=False).energy
                )
            else:
                raise RunFormatError(f"{self.path} has no energy.csv (nor fields.mcap)")
        return self._energy

    def tip_history(self, crack: int = 0, tip: Optional[int] = None) -> pd.DataFrame:
        """The rows of :attr:`crack_tips` of one crack (and one tip of it, if given),
        indexed by ``time`` (s)."""
        df = self.crack_tips
        sel = df[df["crack"] == crack]
        if tip is not None:
            sel = sel[sel["tip"] == tip]
        return sel.set_index("time")

    # ----------------------------------------------------------------- snapshots

    @property
    def mcap_path(self) -> Path:
        """Path of the run's ``fields.mcap``."""
        return self.path / "fields.mcap"

    def snapshots(self, components: Optional[Iterable[str]] = None) -> Iterator[Snapshot]:
        """The field snapshots, in time order, decoded one at a time from ``fields.mcap``.

        Each is a :class:`mpm_fracture.Snapshot` whose components are ``float32`` arrays of
        shape ``(ny, nx)`` (row 0 = lowest y; NaN where no material touches the node): Pa
        for stresses, m/s for velocities, m for displacements (see
        :class:`~mpm_fracture.Snapshot`).

        Args:
            components: only these components (e.g. ``["syy", "fringe"]``); all by
                default.

        Raises:
            RunFormatError: the run has no ``fields.mcap``.
        """
        if not self.mcap_path.exists():
            raise RunFormatError(
                f"{self.path} has no fields.mcap (the scene asked for no snapshots, or the "
                "job has not written any yet)"
            )
        return iter_snapshots(self.mcap_path, components)

    def snapshot(self, index: int, components: Optional[Iterable[str]] = None) -> Snapshot:
        """The snapshot with this ``index`` (``-1``: the last one)."""
        if index < 0:
            snaps = list(self.snapshots(components))
            if not snaps:
                raise IndexError(f"{self.path}: the run has no snapshots")
            return snaps[index]
        for s in self.snapshots(components):
            if s.index == index:
                return s
        raise IndexError(f"{self.path}: no snapshot {index}")

    @property
    def scene(self) -> Optional[Dict[str, Any]]:
        """The run's scene: the job's scene for a service job, else the canonical scene
        stored in ``fields.mcap`` (``None`` when neither is there)."""
        if self.job is not None and self.job.get("scene"):
            return dict(self.job["scene"])
        if self.mcap_path.exists():
            meta = read_mcap(self.mcap_path, snapshots=False).scene
            if meta and meta.get("json"):
                return dict(json.loads(meta["json"]))
        return None

    def __repr__(self) -> str:
        s = self.summary
        bits = [f"Run({str(self.path)!r}"]
        if s:
            bits.append(f"status={s.get('status')!r}, steps={s.get('steps')}, sim_time={s.get('sim_time')}")
        if self.job is not None:
            bits.append(f"job={self.job.get('id')!r}")
        return ", ".join(bits) + ")"


