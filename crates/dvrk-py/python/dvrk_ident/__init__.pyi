"""Type stubs of the dvrk_ident extension module (see README.md for the tutorial).

Arrays are float64 numpy arrays. Functions of the robot state take one sample as 1-D
arrays of ``dof`` values or ``N`` samples as 2-D arrays ``(N, dof)``; outputs then have
a leading sample axis, which a single 1-D sample drops.
"""

import os
import pathlib
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt
from typing_extensions import Unpack

__version__: str

FloatArray = npt.NDArray[np.float64]
ArrayLike = npt.ArrayLike
PathLike = Union[str, "os.PathLike[str]"]
#: A parameter vector (``len(robot.parameter_names)`` values, in that order), a mapping
#: ``{name: value}`` with every parameter, or a fit ``FitResult``.
Params = Union[ArrayLike, Mapping[str, float], "FitResult"]

class DvrkError(Exception):
    """Base class of every error raised by dvrk_ident."""

class InputError(DvrkError, ValueError):
    """Invalid input: arguments, array shapes or values (NaN), robot descriptions, log
    contents, data that do not fit the robot or do not determine the parameters."""

class DvrkIOError(DvrkError, OSError):
    """A file that cannot be read or written."""

class DvrkFileNotFoundError(DvrkIOError, FileNotFoundError):
    """A file that does not exist."""

class SolverError(DvrkError, RuntimeError):
    """A numerical failure (solver, base parameters) or an internal error."""

class NotConvergedError(SolverError):
    """The fit's solver did not converge; ``result`` holds the unconverged FitResult."""

    result: "FitResult"

class Model:
    """A robot model: a built-in dVRK arm (``Model.builtin_names()``: ``"psm"``,
    ``"psm_simplified"``, ``"mtm"``, ``"ecm"``, ``"psm_si"``, ``"psm_si_tool"``,
    ``"ecm_si"``), a ``.toml`` description or a ``.urdf`` file."""

    def __init__(self, name_or_path: PathLike) -> None: ...
    @staticmethod
    def load(name_or_path: PathLike) -> "Model":
        """Loads a built-in robot or a ``.toml``/``.urdf`` file."""
    @staticmethod
    def from_toml(text: str, source: str = "<string>") -> "Model": ...
    @staticmethod
    def from_urdf(text: str, source: str = "<string>") -> "Model": ...
    @staticmethod
    def builtin_names() -> List[str]: ...
    @property
    def name(self) -> str: ...
    @property
    def source(self) -> str:
        """``builtin:psm`` or the file path."""
    @property
    def coordinates(self) -> List[str]:
        """Model coordinate names: the columns of ``q``."""
    @property
    def measured_joints(self) -> List[str]:
        """Measured joint names (e.g. ROS), one per coordinate."""
    @property
    def coupling(self) -> FloatArray:
        """``(dof, dof)``: ``q_measured = coupling @ q_model``."""
    @property
    def parameter_names(self) -> List[str]:
        """Parameter names in regressor column order."""
    @property
    def dof(self) -> int: ...
    @property
    def n_parameters(self) -> int: ...
    @property
    def frame_names(self) -> List[str]:
        """Frame names, base first (the frame axis of ``forward_kinematics``)."""
    @property
    def limits(self) -> Dict[str, Any]:
        """The description's excitation limits in the layout of a limits file:
        ``{"limits": [...], "cartesian_limits": [...]}``; edit a copy and pass it to
        :func:`excite` as ``limits=``."""
    @property
    def gravity_vector(self) -> FloatArray:
        """Gravity in the base frame, m/s², ``(3,)``."""
    @property
    def nominal_parameters(self) -> Optional[FloatArray]:
        """``(n_parameters,)`` nominal values of the description, or ``None``."""
    def summary(self) -> Dict[str, Any]:
        """The document of ``dvrk-ident model ROBOT --json``."""
    def base(self) -> "BaseParameters":
        """The base (identifiable) parameters (computed once per robot)."""
    def regressor(
        self, q: ArrayLike, dq: Optional[ArrayLike] = None, ddq: Optional[ArrayLike] = None
    ) -> FloatArray:
        """``H`` with ``tau = H @ params``: ``(N*dof, n_parameters)`` (row ``k*dof + j``
        is coordinate ``j`` of sample ``k``), ``(dof, n_parameters)`` for one sample."""
    def base_regressor(
        self, q: ArrayLike, dq: Optional[ArrayLike] = None, ddq: Optional[ArrayLike] = None
    ) -> FloatArray:
        """The ``base().independent`` columns of ``regressor``: ``(N*dof, rank)``."""
    def inverse_dynamics(
        self,
        params: Params,
        q: ArrayLike,
        dq: Optional[ArrayLike] = None,
        ddq: Optional[ArrayLike] = None,
    ) -> FloatArray:
        """``tau = H @ params`` without known forces: ``(N, dof)`` or ``(dof,)``."""
    def gravity(self, params: Params, q: ArrayLike) -> FloatArray:
        """Gravity torque of the links: ``(N, dof)`` or ``(dof,)``."""
    def mass_matrix(self, params: Params, q: ArrayLike) -> FloatArray:
        """``M(q)``: ``(N, dof, dof)``, or ``(dof, dof)`` for one 1-D sample."""
    def forward_dynamics(
        self, params: Params, q: ArrayLike, dq: ArrayLike, tau: ArrayLike
    ) -> FloatArray:
        """Accelerations under measured torques: ``(N, dof)`` or ``(dof,)``."""
    def known_forces(self, q: ArrayLike) -> FloatArray:
        """Known generalized forces (e.g. the MTM cable): ``(N, dof)`` or ``(dof,)``."""
    def to_urdf(self, params: Params) -> str:
        """The generated URDF (``dvrk-ident export --urdf``) with these inertials."""
    def forward_kinematics(self, q: ArrayLike) -> FloatArray:
        """Frame poses in the base frame, base first: ``(N, frames, 4, 4)`` or
        ``(frames, 4, 4)``."""

class BaseParameters:
    """``beta = combination @ params``; ``H @ params == H[:, independent] @ beta``."""

    @property
    def names(self) -> List[str]: ...
    @property
    def expressions(self) -> List[str]: ...
    @property
    def independent(self) -> List[int]: ...
    @property
    def combination(self) -> FloatArray:
        """``(rank, n_parameters)``."""
    @property
    def rank(self) -> int: ...
    def __len__(self) -> int: ...
    def project(self, params: Params) -> FloatArray:
        """``beta``, ``(rank,)``."""
    def regressor(
        self, q: ArrayLike, dq: Optional[ArrayLike] = None, ddq: Optional[ArrayLike] = None
    ) -> FloatArray:
        """The base regressor, as ``Model.base_regressor``."""
    def to_dict(self) -> Dict[str, Any]: ...

class JointLog:
    """A joint-space log: times, positions, velocities (optional), efforts. Times are
    float seconds, datetime64/timedelta64 or integer nanoseconds (exact); DataFrame
    columns give the joint names; slices, :meth:`concat`, pickling."""

    def __init__(
        self,
        time: ArrayLike,
        q: ArrayLike,
        tau: ArrayLike,
        dq: Optional[ArrayLike] = None,
        *,
        joint_names: Optional[Sequence[str]] = None,
        coordinates: Optional[str] = None,
        source: str = "numpy",
    ) -> None: ...
    @staticmethod
    def from_dataframe(
        df: Any, robot: Optional[Model] = None, *, time: Optional[str] = None,
        source: str = "dataframe",
    ) -> "JointLog":
        """``time``, ``position.<joint>``, ``velocity.<joint>``, ``effort.<joint>``
        columns (or a ``(signal, joint)`` MultiIndex; the time as a column or the index);
        model or measured coordinates from the names."""
    def to_dataframe(self) -> Any:
        """A pandas DataFrame in the layout :meth:`from_dataframe` reads."""
    @staticmethod
    def concat(logs: Sequence["JointLog"], *, source: Optional[str] = None) -> "JointLog":
        """The samples of several logs as one log (one clock)."""
    @property
    def time(self) -> FloatArray:
        """Sample times, s, ``(N,)``."""
    @property
    def q(self) -> FloatArray:
        """``(N, joints)``, rad or m."""
    @property
    def dq(self) -> Optional[FloatArray]:
        """``(N, joints)``, rad/s or m/s, or ``None``."""
    @property
    def tau(self) -> FloatArray:
        """``(N, joints)``, N·m or N."""
    @property
    def joint_names(self) -> List[str]: ...
    @property
    def coordinates(self) -> str:
        """``"measured"`` or ``"model"``."""
    @property
    def source(self) -> str: ...
    @property
    def path(self) -> Optional[pathlib.Path]:
        """The file the data were read from (absolute), or ``None``."""
    @property
    def dof(self) -> int: ...
    @property
    def rate(self) -> Optional[float]:
        """Sampling rate estimate, Hz."""
    def __len__(self) -> int: ...
    def to_model(self, robot: Model) -> "JointLog":
        """The data in the robot's model coordinates."""
    def write(
        self, path: PathLike, format: Optional[str] = None, topic: Optional[str] = None
    ) -> None:
        """Writes a ``csv``, ``wpi`` or ``mcap`` log atomically."""

class Prepared:
    """Processed samples (known forces subtracted), in the model coordinates or the
    arm's measured joints (``joints``)."""

    @property
    def time(self) -> FloatArray: ...
    @property
    def q(self) -> FloatArray: ...
    @property
    def dq(self) -> FloatArray: ...
    @property
    def ddq(self) -> FloatArray: ...
    @property
    def tau(self) -> FloatArray: ...
    @property
    def joint_names(self) -> List[str]: ...
    @property
    def joints(self) -> str:
        """``"model"`` or ``"measured"``."""
    @property
    def source(self) -> str: ...
    def to_dataframe(self) -> Any:
        """``time``, ``position.<joint>``, ``velocity.<joint>``,
        ``acceleration.<joint>``, ``effort.<joint>``."""
    def __len__(self) -> int: ...

class FitResult:
    """The result document of a fit (``dvrk-ident fit --out``)."""

    @staticmethod
    def from_json(text: str, robot: Optional[Model] = None) -> "FitResult": ...
    @staticmethod
    def read(path: PathLike, robot: Optional[Model] = None) -> "FitResult": ...
    def to_json(self) -> str: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def write(self, path: PathLike) -> None: ...
    @property
    def parameters(self) -> Dict[str, float]: ...
    @property
    def parameter_array(self) -> FloatArray: ...
    @property
    def parameter_order(self) -> List[str]: ...
    @property
    def parameter_status(self) -> Dict[str, str]:
        """``{name: "identified" | "at_lower_bound" | "at_upper_bound" | "unidentified"}``."""
    @property
    def base_parameters(self) -> List[Dict[str, Any]]:
        """``[{name, expression, value, std}]``."""
    @property
    def links(self) -> List[Dict[str, Any]]:
        """``[{frame, link, mass, com, inertia_com, determined}]``, ``determined``
        ``{mass, first_moment, inertia}`` (booleans)."""
    @property
    def consistency(self) -> List[Dict[str, Any]]:
        """``[{frame, link, min_eigenvalue, consistent}]``."""
    @property
    def physically_consistent(self) -> bool: ...
    @property
    def solver(self) -> Dict[str, Any]:
        """``{name, status, converged, seconds, iterations}`` (and ``tolerance``)."""
    @property
    def delay(self) -> Optional[Dict[str, Any]]:
        """``{delay_s, std_s, max_s, residual, sweeps}`` of ``delay="auto"``, or None."""
    @property
    def selection(self) -> Optional[Dict[str, Any]]:
        """The friction model chosen by held-out error (``select=``): ``{folds, joints,
        candidates: [{candidate, relative_error, mean}], chosen}``, or None."""
    @property
    def prior_divergence(self) -> Optional[float]:
        """With an entropic prior: the links' summed log-det divergence from it, or None."""
    @property
    def payload(self) -> Optional[Dict[str, Any]]:
        """The payload the arm carries (:func:`identify_payload`): ``{frame, mass, com,
        inertia, identification}`` (kg, m, kg·m² about the com ``xx yy zz xy xz yz``),
        or None. ``parameters`` stay the arm's; validate and the exports add it."""
    @property
    def metrics(self) -> Dict[str, Any]:
        """``{train, test}``, each ``{joints, samples, relative_error, rms}`` or None."""
    @property
    def settings(self) -> Dict[str, Any]: ...
    @property
    def inputs(self) -> List[Dict[str, Any]]: ...
    @property
    def method(self) -> str: ...
    @property
    def robot(self) -> str:
        """The robot's name."""
    @property
    def robot_source(self) -> str: ...
    @property
    def tool(self) -> str: ...
    @property
    def weights(self) -> FloatArray: ...
    @property
    def rows(self) -> int: ...
    @property
    def condition_number(self) -> float: ...
    @property
    def sigma2(self) -> float: ...
    def load_robot(self) -> Model: ...
    def prepare(
        self, data: JointLog, robot: Optional[Model] = None, *, joints: Optional[str] = None
    ) -> Prepared: ...
    def predict(
        self, data: Union[JointLog, Prepared], robot: Optional[Model] = None, *,
        as_dataframe: bool = False, joints: Optional[str] = None,
    ) -> Any:
        """Predicted torques ``(N, dof)`` at the processed samples of ``data``
        (rows of ``self.prepare(data)``), known forces excluded, in ``joints``
        (``"model"`` or ``"measured"``; default a Prepared's own, else the fit's); with
        ``as_dataframe``, a DataFrame with ``time`` and ``effort.<joint>`` columns."""
    def validate(
        self, data: JointLog, test_window: Optional[int] = None, robot: Optional[Model] = None,
        *, joints: Optional[str] = None,
    ) -> Dict[str, Any]:
        """The errors on ``data`` with the result's model and processing; with
        ``log_offsets`` the model's ``Fo`` (the first training log's) apply, not the
        other training logs' own offsets."""
    def wpi_params(self, robot: Optional[Model] = None) -> Dict[str, Any]: ...
    def dvrk_gc(self, robot: Optional[Model] = None, points: int = 7) -> Dict[str, Any]:
        """The dVRK controller's MTM gravity-compensation file (version "2.0")."""
    def dvrk_kinematic_gc(
        self, robot: Optional[Model] = None, *, endoscope: Optional[str] = None
    ) -> Dict[str, Any]:
        """The dVRK controller's kinematic gravity-compensation file (the physical DH
        of its ``kinematic_gc`` key) of an ecm, psm_si (psm_si_tool) or ecm_si result."""

def read_log(
    path: PathLike,
    robot: Optional[Model] = None,
    format: Optional[str] = None,
    rate: Optional[float] = None,
    topic: Optional[Union[str, Sequence[str]]] = None,
    time_source: Optional[str] = None,
    resample: Optional[float] = None,
    max_unpacked_mib: Optional[int] = None,
) -> JointLog:
    """Reads a log recognized by content: a rosbag2 folder (or its metadata.yaml), an
    MCAP, sqlite3 .db3 or ROS 1 .bag file (zstd/lz4 compressed too), a 2019 CSV
    (``rate`` required) or a headered CSV; ``resample`` (Hz) resamples any format;
    ``max_unpacked_mib`` bounds what a compressed recording may decompress to (MiB;
    default 100 times its size within 64 MiB and 16 GiB)."""

def list_topics(path: PathLike) -> List[Dict[str, Any]]:
    """The topics of a recording (MCAP, sqlite3, ROS 1 bag or rosbag2 folder)."""

# The fit options a function takes as keywords (``**options``, ``dvrk_ident._options``:
# each function's, in the library's order), each written once: a class per set, a set
# that adds options to another derives from it. Each may be left out or None: the
# ``settings`` (or the library's default) then apply.

class ProcessingOptions(TypedDict, total=False):
    """How a log is processed (``dvrk_ident._options["prepare"]``, also
    ``["external_torque"]``): ``cutoff`` (Hz, per coordinate, or ``"none"``/``False``),
    ``filter_order``, ``filter_torque``, ``trim`` and ``decimate`` (samples),
    ``min_speed`` (rad/s or m/s), ``resample`` (Hz)."""

    cutoff: Optional[Union[float, Sequence[float], str, bool]]
    filter_order: Optional[int]
    filter_torque: Optional[bool]
    trim: Optional[int]
    decimate: Optional[int]
    min_speed: Optional[float]
    resample: Optional[float]

class ObserveOptions(ProcessingOptions, total=False):
    """:func:`observe`'s (``dvrk_ident._options["observe"]``): the processing, the
    Stribeck terms and the mounting (degrees)."""

    stribeck: Optional[float]
    mounting_pitch: Optional[float]

class FitOptions(ProcessingOptions, total=False):
    """:func:`fit`'s (``dvrk_ident._options["fit"]``; ``method`` is its positional
    argument)."""

    test_window: Optional[int]
    irls_iterations: Optional[int]
    sdp_regularization: Optional[float]
    stribeck: Optional[float]
    dahl: Optional[float]
    position_torque: Optional[int]
    position_torque_frames: Optional[Union[str, Sequence[str]]]
    load_friction: Optional[bool]
    mounting_pitch: Optional[float]
    bounds: Optional[str]
    ellipsoids: Optional[bool]
    delay: Optional[Union[str, float, Sequence[float]]]
    prior: Optional[Union[str, PathLike, "FitResult"]]
    prior_weight: Optional[float]
    prior_metric: Optional[str]
    preset: Optional[str]
    log_offsets: Optional[bool]
    select: Optional[Union[str, bool, Sequence[str]]]
    joints: Optional[str]

class Observation:
    """Training logs reduced to their R factors (:func:`observe`): merge with ``+``,
    fit with :func:`fit`; ``bytes()`` is the file of ``dvrk-ident observe``."""

    @staticmethod
    def from_bytes(data: bytes) -> "Observation": ...
    @staticmethod
    def read(path: PathLike) -> "Observation": ...
    def write(self, path: PathLike) -> None: ...
    def merge(self, other: "Observation") -> "Observation": ...
    def __add__(self, other: "Observation") -> "Observation": ...
    def __bytes__(self) -> bytes: ...
    @property
    def robot(self) -> str: ...
    @property
    def samples(self) -> int: ...
    @property
    def logs(self) -> List[Dict[str, Any]]:
        """``[{path, sha256, bytes, source, samples}]``."""
    @property
    def processing(self) -> Dict[str, Any]: ...

def observe(
    robot: Model,
    data: Union[JointLog, PathLike, Sequence[Union[JointLog, PathLike]]],
    *,
    settings: Optional[Mapping[str, Any]] = None,
    **options: Unpack[ObserveOptions],
) -> Observation:
    """The logs processed as :func:`fit` processes them and reduced: the map of a fit
    over many processes or machines."""

def fit(
    robot: Model,
    data: Union[JointLog, Sequence[JointLog], Observation, Sequence[Observation]],
    method: Optional[str] = None,
    *,
    test: Optional[Union[JointLog, Sequence[JointLog]]] = None,
    excitation: Optional[Union[FourierTrajectory, PathLike]] = None,
    settings: Optional[Mapping[str, Any]] = None,
    allow_unconverged: bool = False,
    **options: Unpack[FitOptions],
) -> FitResult:
    """Identifies the parameters from one log or a list of logs, each processed on its
    own, or from observations (:func:`observe`, merged in order) (``method``: ``ols``, ``wls``, ``irls``, ``sdp`` (default)); ``cutoff``: Hz,
    per coordinate, or ``"none"``/``False`` (no filter); ``bounds``: ``"physical"`` or
    ``"2019"``; ``ellipsoids=False``: ignore the links' bounding ellipsoids of the
    description (``--no-ellipsoids``); ``mounting_pitch``: degrees, gravity
    ``(0, -9.81 sin p, -9.81 cos p)`` in the base frame (``--mounting-pitch``); ``delay``: ``"auto"`` or seconds (one, or one per coordinate);
    ``dahl``: Dahl friction of this stiffness (1/rad or 1/m) on every friction element (``--dahl``);
    ``position_torque``: a Fourier series of this order (1 to 3; 0: none) in the joint angle on every
    revolute friction element (``--position-torque``), or on the frames named by
    ``position_torque_frames`` (``"upper_arm,forearm"`` or a list); ``load_friction=True``: Coulomb friction in proportion to
    each coordinate's torque (``--load-friction``);
    ``preset``: ``"dvrk"`` (``method="sdp"``, ``stribeck=0.3``, ``dahl=20``, and
    ``prior="nominal"``, ``prior_weight=0.05`` for an sdp fit of a robot with nominal
    masses, and the description's ``[preset]``: the MTM's ``position_torque=1``,
    ``position_torque_frames="upper_arm,forearm"``, for the keywords not given;
    ``prior="none"`` leaves the prior out, ``position_torque=0`` the position torque); ``log_offsets=True``: every log after the first gets its own
    torque offset per coordinate (``inputs[k]["offset"]``; the model's ``Fo`` are the
    first log's); ``select``: ``True``/``"builtin"`` or candidate names
    (``["coulomb", "stribeck:0.2+dahl"]``): the friction model chosen by held-out error
    (leave one log out, or 4 blocks in time), the table in :attr:`FitResult.selection`; ``prior``: ``"nominal"``, a result file or a :class:`FitResult` to regularize the
    semidefinite fit toward, ``prior_weight`` (default 0.001), ``prior_metric``:
    ``"entropic"`` (default) or ``"euclidean"``."""

def prepare(
    robot: Model,
    data: JointLog,
    *,
    settings: Optional[Mapping[str, Any]] = None,
    **options: Unpack[ProcessingOptions],
) -> Prepared:
    """The processed samples the estimators see."""

def compare(
    a: FitResult,
    b: FitResult,
    test: Optional[Union[JointLog, Sequence[JointLog]]] = None,
    *,
    test_window: Optional[int] = None,
    names: Optional[Tuple[str, str]] = None,
) -> Dict[str, Any]:
    """Two results side by side (``dvrk-ident compare --json``): the settings that
    differ, the base parameters with their standard deviations and the difference in
    combined standard deviations, every parameter and link mass, and each result's
    per-joint errors on the ``test`` logs with its own model and processing."""

def identify_payload(
    result: FitResult,
    data: Union[JointLog, Sequence[JointLog]],
    *,
    frame: str,
    robot: Optional[Model] = None,
) -> FitResult:
    """A rigid payload fixed to ``frame`` estimated from logs of the arm carrying it,
    the rest of the model held at ``result`` (``dvrk-ident payload``): ``result`` with
    the payload added (:attr:`FitResult.payload`, with what the logs determine and the
    standard deviations under ``identification``)."""
def external_torque(
    result: FitResult,
    data: JointLog,
    robot: Optional[Model] = None,
    *,
    observer_gain: float = 20.0,
    joints: Optional[str] = None,
    wrench: Optional[str] = None,
    wrench_rcond: float = 1e-6,
    as_dataframe: bool = False,
    **options: Unpack[ProcessingOptions],
) -> Any:
    """``dvrk-ident residual``: per processed sample ``tau_measured − tau_model`` and the
    momentum observer's estimate, with the result's processing (the keywords replace
    it). A dict ``{source, joints, time (N,), residual (N, dof), observer (N, dof),
    rms (dof,), noise_floor (dof,) or None, observer_gain}``; with ``as_dataframe``, a
    DataFrame of ``time``, ``residual.<joint>``, ``observer.<joint>`` (the rest in its
    ``attrs``). With ``wrench`` (a frame, e.g. ``"tool_tip"``; ``--wrench``), its
    ``wrench`` entry is ``{frame, rcond, components, base (N, 6), tip (N, 6), rank (N,),
    unsensed_base, unsensed_tip}``: the least-squares wrench of ``tau_ext = Jᵀ·F`` at the
    frame's origin (force N, moment N·m) in the base frame's and the frame's own axes,
    the directions sensed per sample, and per sample the ``(6 − rank, 6)`` unsensed
    directions (``None`` without ``wrench``); the DataFrame adds ``wrench_base.<c>``,
    ``wrench_tip.<c>`` and ``wrench_rank``."""

class MomentumObserver:
    """The generalized-momentum observer (real time): ``update(q, dq, tau, dt)`` returns
    the estimate of ``tau − tau_model`` (N·m or N), each coordinate a first-order lag of
    time constant ``1/gain`` s; the first update after construction or :meth:`reset`
    returns zeros."""

    def __init__(
        self, robot: Model, params: Params, gains: Union[float, ArrayLike] = 20.0
    ) -> None: ...
    def update(
        self, q: ArrayLike, dq: ArrayLike, tau: ArrayLike, dt: Union[float, ArrayLike]
    ) -> FloatArray:
        """One sample ``(dof,)`` → ``(dof,)``, or ``N`` consecutive samples ``(N, dof)``
        → ``(N, dof)``; ``dt`` (s, positive): the step before each sample."""
    def reset(self) -> None: ...
    @property
    def gains(self) -> FloatArray:
        """``(dof,)``, 1/s."""
    @property
    def estimate(self) -> FloatArray:
        """The current estimate, ``(dof,)``."""
    @property
    def dof(self) -> int: ...

#: Limits of an excitation: None (the robot description's), a limits file (TOML with
#: ``[[limits]]`` and ``[[cartesian_limits]]`` tables) or a dict in that layout.
LimitsArg = Optional[Union[PathLike, Mapping[str, Any]]]

class FourierTrajectory:
    """A periodic Fourier excitation trajectory per model coordinate (the JSON of
    ``dvrk-ident excite``): ``q_j(t) = q0_j + Σ_l (a_jl sin(l w t) − b_jl cos(l w t))
    / (l w)``, ``w = 2π f0``."""

    def __init__(
        self,
        order: int,
        base_frequency_hz: float,
        q0: ArrayLike,
        a: ArrayLike,
        b: ArrayLike,
        coordinates: Optional[Sequence[str]] = None,
    ) -> None: ...
    @staticmethod
    def read(path: PathLike, pick: Optional[str] = None) -> "FourierTrajectory":
        """A trajectory JSON file, or with ``pick`` one trajectory of a 2019-layout
        coefficient file."""
    @staticmethod
    def from_json(text: str, source: str = "<string>") -> "FourierTrajectory": ...
    @staticmethod
    def wpi_names(path: PathLike) -> List[str]: ...
    @staticmethod
    def wpi2019_names(path: PathLike) -> List[str]:
        """Deprecated name of :meth:`wpi_names` (warns)."""
    @property
    def order(self) -> int: ...
    @property
    def base_frequency_hz(self) -> float: ...
    @property
    def period(self) -> float:
        """``1 / f0``, s."""
    @property
    def dof(self) -> int: ...
    @property
    def q0(self) -> FloatArray:
        """``(dof,)``, rad or m."""
    @property
    def a(self) -> FloatArray:
        """``(dof, order)``, rad/s or m/s."""
    @property
    def b(self) -> FloatArray:
        """``(dof, order)``, rad/s or m/s."""
    @property
    def coordinates(self) -> List[str]: ...
    def sample(self, time: ArrayLike) -> "tuple[FloatArray, FloatArray, FloatArray]":
        """``(q, dq, ddq)``, each ``(N, dof)``, at the times (s)."""
    def setpoints(self, robot: Model, rate: float = 200.0) -> "tuple[FloatArray, FloatArray]":
        """One period at ``rate`` Hz in measured joint space: ``(time (N,), q (N, m))``."""
    def to_json(self) -> str: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def write(self, path: PathLike) -> None: ...

class Excitation:
    """An optimized trajectory with its criterion and dense feasibility check."""

    @property
    def trajectory(self) -> FourierTrajectory: ...
    @property
    def criterion(self) -> Dict[str, Any]:
        """``{"name": "condition" | "log_det", "value": float}``."""
    @property
    def feasible(self) -> bool: ...
    @property
    def feasibility(self) -> Dict[str, Any]:
        """``{feasible, samples, rate_hz, worst, violated}``."""
    @property
    def starts(self) -> List[Optional[float]]: ...
    def to_json(self) -> str: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def write(self, path: PathLike) -> None: ...

def excite(
    robot: Model,
    order: int = 6,
    f0: float = 0.18,
    *,
    limits: LimitsArg = None,
    init: Optional[FourierTrajectory] = None,
    # The excitation options (dvrk_ident._excite_options["excite"]: the library's order
    # and defaults, which a test checks these against).
    criterion: str = "condition",
    seed: int = 0,
    starts: int = 8,
    refine: int = 3,
    iterations: int = 110,
    refine_iterations: int = 180,
    samples_per_harmonic: int = 15,
    rest: bool = False,
    smooth: bool = True,
    check_rate: float = 1000.0,
) -> Excitation:
    """Optimizes an excitation trajectory (``dvrk-ident excite``): condition number
    (or ``"log_det"``) of the base regressor under the limits; raises ``SolverError``
    when no feasible trajectory is found, ``InputError`` for impossible limits."""

def evaluate_trajectory(
    robot: Model,
    trajectory: FourierTrajectory,
    *,
    limits: LimitsArg = None,
    # dvrk_ident._excite_options["evaluate_trajectory"].
    criterion: str = "condition",
    samples_per_harmonic: int = 15,
    check_rate: float = 1000.0,
) -> Dict[str, Any]:
    """``dvrk-ident excite --evaluate --json``: ``{criterion, feasible,
    worst_violation, violated, check_samples, check_rate_hz}``."""

# The names of the development builds before 0.1.0, kept until 0.2.0: accessing them warns
# (DeprecationWarning) and gives the class of the new name.
Robot = Model
Data = JointLog
Result = FitResult
Trajectory = FourierTrajectory
