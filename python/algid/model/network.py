"""A spring network: n masses (DOF 1..n), springs between any two of them or to ground
(DOF 0), a viscous damper from every mass to ground. The chain of eq. 1 is one such network
(:meth:`Network.chain`); every topology question of the model (the stiffness matrix, the
deformations, which springs enter which DOF's equation) is answered here.

Spring ``s = (a, b)`` has stiffness ``k_s`` and deformation ``d_s = x_b - x_a`` [m]
(``x_0 = 0``). DOF ``i``'s equation is

    m_i x_i'' + c_i x_i' + sum_{s incident on i} k_s (x_i - x_other(s)) = u_i,

so ``K = D^T diag(k) D`` with ``d = D x``. Springs in parallel (the same two ends) give the
same column in every equation: only their sum is identifiable, and the equation's column is
attributed to the first of them.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

BOUNDARIES = ("fixed", "free")


@dataclass(frozen=True)
class Network:
    """Topology of ``n`` masses and the springs ``(a, b)`` (1-based DOFs, 0 = ground)."""

    n: int
    springs: tuple[tuple[int, int], ...]

    def __init__(self, n: int, springs=()) -> None:
        if int(n) != n or n < 1:
            raise ValueError(f"a network needs n >= 1 masses, got {n!r}")
        pairs = tuple((int(a), int(b)) for a, b in springs)
        for s, (a, b) in enumerate(pairs, start=1):
            for end in (a, b):
                if not 0 <= end <= n:
                    raise ValueError(f"spring k{s} = ({a}, {b}) joins DOF {end}, outside 0..{n} (0 is ground)")
            if a == b:
                raise ValueError(f"spring k{s} = ({a}, {b}) joins DOF {a} to itself")
        object.__setattr__(self, "n", int(n))
        object.__setattr__(self, "springs", pairs)

    @classmethod
    def chain(cls, n: int, boundary: str = "fixed") -> Network:
        """Eq. 1: spring ``j`` joins DOF ``j-1`` and ``j`` (DOF 0 the left wall); with
        ``boundary="fixed"`` spring ``n+1`` joins DOF ``n`` to the right wall (ground), with
        ``"free"`` it is absent. For n = 1 with walls both springs join DOF 1 to ground (in
        parallel: one identifiable sum, attributed to ``k1``)."""
        if boundary not in BOUNDARIES:
            raise ValueError(f"boundary must be one of {BOUNDARIES}, got {boundary!r}")
        pairs = [(j - 1, j) for j in range(1, n + 1)]
        if boundary == "fixed":
            pairs.append((n, 0))
        return cls(n, pairs)

    # --- JSON ------------------------------------------------------------------------------

    @classmethod
    def from_json(cls, source) -> Network:
        """The network of ``{"n": N, "springs": [[a, b], ...]}`` (a dict or a path of its JSON)."""
        doc = json_document(source)
        if not isinstance(doc, dict) or not {"n", "springs"} <= set(doc):
            raise ValueError(f"{source if not isinstance(source, dict) else 'network'}: needs keys n and springs")
        bad = [p for p in doc["springs"] if not (isinstance(p, (list, tuple)) and len(p) == 2)]
        if bad:
            raise ValueError(f"every spring is a pair [a, b] of DOFs (0 = ground), got {bad[0]!r}")
        return cls(doc["n"], [tuple(p) for p in doc["springs"]])

    def to_json(self, path=None) -> dict:
        """``{"n": N, "springs": [[a, b], ...]}``, also written to ``path`` if given."""
        doc = {"n": self.n, "springs": [list(p) for p in self.springs]}
        if path is not None:
            Path(path).write_text(json.dumps(doc) + "\n", encoding="utf-8")
        return doc

    # --- topology ---------------------------------------------------------------------------

    @property
    def size(self) -> int:
        """Number of springs S."""
        return len(self.springs)

    def parameter_names(self) -> list[str]:
        """``m1..mn, c1..cn, k1..kS``: the order of every packed parameter vector."""
        n = self.n
        return (
            [f"m{i}" for i in range(1, n + 1)]
            + [f"c{i}" for i in range(1, n + 1)]
            + [f"k{s}" for s in range(1, self.size + 1)]
        )

    def deformation_matrix(self) -> np.ndarray:
        """``D`` (S, n) with ``d = D x``: ``d_s = x_b - x_a`` [m] for spring ``s = (a, b)``."""
        D = np.zeros((self.size, self.n))
        for s, (a, b) in enumerate(self.springs):
            if b:
                D[s, b - 1] += 1.0
            if a:
                D[s, a - 1] -= 1.0
        return D

    def stiffness_matrix(self, k) -> np.ndarray:
        """Stiffness matrix ``K = D^T diag(k) D`` (n, n) [N/m] from the springs ``k`` (S,) [N/m]."""
        k = np.asarray(k, dtype=float).reshape(-1)
        if k.size != self.size:
            raise ValueError(f"{k.size} spring stiffnesses for a network of {self.size} springs")
        D = self.deformation_matrix()
        return D.T @ (k[:, None] * D)

    def deformation(self, x: np.ndarray, s: int) -> np.ndarray:
        """Deformation ``d_s = x_b - x_a`` (T,) [m] of spring ``s`` (1-based) from positions ``x`` (T, n)."""
        a, b = self.springs[s - 1]
        x = np.asarray(x, dtype=float)
        right = x[:, b - 1] if b else 0.0
        left = x[:, a - 1] if a else 0.0
        return right - left

    def incident(self, i: int) -> list[tuple[int, float, int]]:
        """``(s, sign, other)`` for every spring ``s`` (1-based) on DOF ``i`` (1-based): its
        force enters DOF i's equation as ``sign k_s d_s = k_s (x_i - x_other)`` (other 0: ground)."""
        out = []
        for s, (a, b) in enumerate(self.springs, start=1):
            if b == i:
                out.append((s, 1.0, a))
            elif a == i:
                out.append((s, -1.0, b))
        return out

    def degree(self, i: int) -> int:
        """Number of springs on DOF ``i`` (1-based)."""
        return len(self.incident(i))

    def parallel_groups(self) -> list[list[int]]:
        """Springs (1-based) grouped by their two ends, in spring order; a group of more than
        one is springs in parallel."""
        groups: dict[frozenset, list[int]] = {}
        for s, (a, b) in enumerate(self.springs, start=1):
            groups.setdefault(frozenset((a, b)), []).append(s)
        return list(groups.values())

    def columns(self, i: int) -> list[tuple[int, int]]:
        """The spring columns of DOF ``i``'s equation (1-based): ``(s, other)`` per distinct other
        end, ``x_i - x_other`` the column and ``s`` the first spring to that end (springs in
        parallel share one column, their sum)."""
        out: list[tuple[int, int]] = []
        for s, _, other in self.incident(i):
            if all(o != other for _, o in out):
                out.append((s, other))
        return out

    def identifiable_springs(self) -> list[int]:
        """Springs (1-based) with an estimate of their own: the first of every parallel group."""
        return [g[0] for g in self.parallel_groups()]

    def sides(self, s: int) -> list[tuple[int, float]]:
        """``(DOF (1-based), sign)`` of every mass spring ``s`` (1-based) pushes (ground left out)."""
        a, b = self.springs[s - 1]
        return [(end, sign) for end, sign in ((b, 1.0), (a, -1.0)) if end]

    # --- identifiability --------------------------------------------------------------------

    def identifiability(self, measured=None, forced=None) -> dict[str, str]:
        """Why each parameter that a recording cannot give is not identifiable (an empty dict:
        all are). ``measured``, ``forced``: 1-based DOFs with a motion sensor and with a force
        (default: every DOF). Reasons: springs in parallel (only their sum), a spring to an
        unmeasured DOF, a DOF without a force nor a path of springs to a forced DOF (no scale)."""
        all_dofs = set(range(1, self.n + 1))
        measured = all_dofs if measured is None else set(measured)
        forced = all_dofs if forced is None else set(forced)
        reasons: dict[str, str] = {}
        for i in sorted(all_dofs - measured):
            reasons[f"m{i}"] = reasons[f"c{i}"] = f"DOF {i} is not measured"
        for s, (a, b) in enumerate(self.springs, start=1):
            blind = [e for e in (a, b) if e and e not in measured]
            if blind:
                reasons[f"k{s}"] = f"k{s} joins DOF {blind[0]}, which is not measured"
        for group in self.parallel_groups():
            if len(group) > 1:
                names = [f"k{s}" for s in group]
                a, b = self.springs[group[0] - 1]
                for name in names:
                    reasons.setdefault(
                        name, f"{', '.join(names)} in parallel between {_end(a)} and {_end(b)}: only their sum"
                    )
        for part in self.components(measured):
            if not part & forced:
                dofs = ", ".join(str(i) for i in sorted(part))
                why = f"no force on DOF {dofs} nor a path of springs to a forced DOF: no scale"
                for i in part:
                    reasons.setdefault(f"m{i}", why)
                    reasons.setdefault(f"c{i}", why)
                    for s, _, _ in self.incident(i):
                        reasons.setdefault(f"k{s}", why)
        return reasons

    def components(self, measured=None) -> list[set[int]]:
        """Groups of measured DOFs (1-based; default: every DOF) joined by springs between
        measured DOFs (the paths along which a spring estimated in both its DOFs carries the
        scale of a force)."""
        measured = set(range(1, self.n + 1)) if measured is None else set(measured)
        parent = {i: i for i in measured}

        def root(i: int) -> int:
            while parent[i] != i:
                i = parent[i]
            return i

        for a, b in self.springs:
            if a in measured and b in measured:
                parent[root(a)] = root(b)
        groups: dict[int, set[int]] = {}
        for i in measured:
            groups.setdefault(root(i), set()).add(i)
        return list(groups.values())


def topology(n: int, boundary) -> Network:
    """The network of a record of ``n`` DOFs: ``boundary`` itself when it is a
    :class:`Network` (of ``n`` masses), else the chain :meth:`Network.chain` ``(n, boundary)``."""
    if not isinstance(boundary, Network):
        return Network.chain(n, boundary)
    if boundary.n != n:
        raise ValueError(f"the topology has {boundary.n} masses, the record {n} DOFs")
    return boundary


#: The keys every model document holds (:func:`read_model_json`).
MODEL_KEYS = ("n", "mass", "damping", "stiffness")


def json_document(source):
    """``source`` itself when it is a dict, else the JSON read from the path ``source`` (a
    one-line ``ValueError`` when it is not JSON)."""
    if isinstance(source, dict):
        return source
    try:
        return json.loads(Path(source).read_text(encoding="utf-8"))
    except json.JSONDecodeError as err:
        raise ValueError(f"{source}: not JSON ({err.msg}, line {err.lineno})") from None


def checked_packed(names: list[str], theta: np.ndarray, what: str) -> np.ndarray:
    """The packed parameters ``theta`` (named ``names``) of a model read back, after checking
    that every one is estimated and admissible (``m > 0``, ``c >= 0``, ``k >= 0``); ``what``
    names the model in the one-line ``ValueError``."""
    missing = [name for name, v in zip(names, theta) if not np.isfinite(v)]
    if missing:
        raise ValueError(f"no estimate of {', '.join(missing)}: a {what} needs every parameter")
    bad = [f"{name} = {v:.4g}" for name, v in zip(names, theta) if v < 0 or (name[0] == "m" and v == 0)]
    if bad:
        raise ValueError(f"inadmissible estimates {', '.join(bad)}: a {what} needs m > 0, c >= 0, k >= 0")
    return theta


def read_model_json(source) -> dict:
    """The document of a model file (a dict, or a path of its JSON): an ``algid identify
    --json`` result, a diagnosis's model, or a hand-written model. Raises a one-line
    ``ValueError`` unless it is a JSON object with the keys :data:`MODEL_KEYS`."""
    doc, name = json_document(source), "model" if isinstance(source, dict) else str(source)
    if not isinstance(doc, dict) or not set(MODEL_KEYS) <= set(doc):
        topology = isinstance(doc, dict) and {"n", "springs"} <= set(doc)
        hint = ": a topology without values (read it with algid.Network.from_json)" if topology else ""
        raise ValueError(f"{name}: not an algid model or identify result (needs {', '.join(MODEL_KEYS)}){hint}")
    return doc


def _end(i: int) -> str:
    return "ground" if i == 0 else f"DOF {i}"


def set_parameters(model, m: np.ndarray, c: np.ndarray, k: np.ndarray) -> None:
    """Check the signs of a model's masses, dampings and springs and set them (frozen dataclass)."""
    if np.any(m <= 0) or np.any(c < 0) or np.any(k < 0):
        raise ValueError("masses must be > 0, dampings and stiffnesses >= 0")
    object.__setattr__(model, "mass", m)
    object.__setattr__(model, "damping", c)
    object.__setattr__(model, "stiffness", k)


@dataclass(frozen=True)
class NetworkModel:
    """Physical parameters of a spring network.

    Parameters
    ----------
    network : the topology.
    mass : (n,) masses m_i [kg]
    damping : (n,) viscous dampings c_i to ground [N s/m]
    stiffness : (S,) spring stiffnesses k_s [N/m], in the network's spring order.
    """

    network: Network
    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray

    def __post_init__(self) -> None:
        m = np.asarray(self.mass, dtype=float).reshape(-1)
        c = np.asarray(self.damping, dtype=float).reshape(-1)
        k = np.asarray(self.stiffness, dtype=float).reshape(-1)
        n, S = self.network.n, self.network.size
        if m.size != n or c.size != n:
            raise ValueError(f"mass and damping need n = {n} entries, got {m.size} and {c.size}")
        if k.size != S:
            raise ValueError(f"stiffness has {k.size} entries, the network has {S} springs")
        set_parameters(self, m, c, k)

    @property
    def n(self) -> int:
        """Number of degrees of freedom."""
        return self.network.n

    def deformation_matrix(self) -> np.ndarray:
        """``D`` (S, n) of the network (``d = D x``)."""
        return self.network.deformation_matrix()

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass, damping and stiffness matrices (M, C, K)."""
        return np.diag(self.mass), np.diag(self.damping), self.network.stiffness_matrix(self.stiffness)

    def natural_frequencies_hz(self) -> np.ndarray:
        """Undamped natural frequencies [Hz], ascending (eigenvalues of M^-1 K)."""
        M, _, K = self.matrices()
        lam = np.linalg.eigvals(np.linalg.solve(M, K)).real
        return np.sort(np.sqrt(np.clip(lam, 0.0, None))) / (2 * np.pi)

    def packed(self) -> np.ndarray:
        """``m1..mn, c1..cn, k1..kS`` (2n+S,)."""
        return np.concatenate([self.mass, self.damping, self.stiffness])

    @classmethod
    def from_packed(cls, theta, network: Network) -> NetworkModel:
        """The model of packed estimates ``m1..mn, c1..cn, k1..kS`` (2n+S,) as ``algid identify``
        reports them on ``network``: the second and later springs of a parallel group (NaN,
        their sum reported in the first) become 0, which leaves K unchanged. Raises a one-line
        ``ValueError`` naming every other parameter without an estimate or with an inadmissible one."""
        theta = np.array(theta, dtype=float).reshape(-1)
        names, n = network.parameter_names(), network.n
        if theta.size != len(names):
            raise ValueError(f"{theta.size} packed parameters, expected 2n+S = {len(names)} for this network")
        for group in network.parallel_groups():
            for s in group[1:]:
                theta[2 * n + s - 1] = 0.0 if not np.isfinite(theta[2 * n + s - 1]) else theta[2 * n + s - 1]
        theta = checked_packed(names, theta, "network model")
        return cls(network, theta[:n], theta[n : 2 * n], theta[2 * n :])

    @classmethod
    def from_json(cls, source) -> NetworkModel:
        """The network model a JSON document (a dict or a path of its JSON) describes: an
        ``algid identify --topology`` result, ``algid diagnose --topology``'s ``--model`` file or
        ``corrected_model``, or a hand-written ``{"n", "springs", "mass", "damping",
        "stiffness"}``. ``stiffness[s-1]`` is spring ``s = springs[s-1]``; ``null`` on a later
        spring of a parallel group is 0 (:meth:`from_packed`). A chain's document (``boundary``
        instead of ``springs``, as :meth:`algid.Chain.from_json` reads) is the network
        :meth:`Network.chain` of the same chain."""
        doc = read_model_json(source)
        if "springs" not in doc:
            from .chain import Chain

            return Chain.from_json(doc).to_network()
        net = Network.from_json({"n": doc["n"], "springs": doc["springs"]})
        packed = [np.nan if v is None else v for v in doc["mass"] + doc["damping"] + doc["stiffness"]]
        return cls.from_packed(packed, net)

    def to_json(self, path=None) -> dict:
        """``{"n", "springs", "mass", "damping", "stiffness"}`` (what :meth:`from_json` reads),
        also written to ``path`` if given."""
        doc = {
            **self.network.to_json(),
            "mass": self.mass.tolist(),
            "damping": self.damping.tolist(),
            "stiffness": self.stiffness.tolist(),
        }
        if path is not None:
            Path(path).write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
        return doc

    def modes(self, sigma=None, covariance=None):
        """Damped modes (:func:`algid.model.modal.modal_analysis`), with uncertainties from the
        standard deviations ``sigma`` (2n+S,) or the ``covariance`` of ``m, c, k`` if given."""
        from .modal import modal_analysis

        return modal_analysis(self, sigma=sigma, covariance=covariance)
