# SPDX-License-Identifier: Apache-2.0
"""Network descriptions for the CANopen manager (:meth:`canola.Master.boot`): which slaves
the network has, what each must be, how it is configured, how the network starts.

From a YAML file::

    start: all              # all: one NMT start to every node (when every slave booted);
                            # each: one per slave (default); none: the application starts
    master_start: true      # the master enters OPERATIONAL with the network (default)
    reset_slaves: false     # NMT reset communication of each slave before booting
    nodes:
      - id: 2
        mandatory: true     # the network waits for it (default); or optional: true
        identity: {device_type: 0x191, vendor: 0xCA0, product: 1, revision: 0x10000,
                   serial: 0}          # each one optional; 0 or missing = not checked
        dcf: drive2.dcf     # its ParameterValues become the concise DCF (path relative
                            # to the YAML file); with no identity given, the DCF's 0x1000
                            # and 0x1018 values are expected
        heartbeat_ms: 500   # the master watches its heartbeat (0x1016) with this time;
                            # the slave must produce one (0x1017, e.g. from its DCF),
                            # else its boot fails with K
        boot_on_bootup: true   # boot it again when it sends a boot-up later (default)
        keep_alive: false      # spared by reset_slaves
      - id: 3
        optional: true

or from DCF files alone (:func:`from_dcfs`): each DCF is one mandatory slave at its
``[DeviceComissioning] NodeID``, identity from its 0x1000/0x1018 values, configuration
from its ParameterValues.

Every problem raises :class:`NetworkError` naming the file and the key
(``net.yaml: nodes[1].identity.vendor: expected an integer, got 'x'``).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from canola.errors import EdsError, Error
from canola.formats import concise, eds

__all__ = ["Identity", "Network", "NetworkError", "SlaveSpec", "from_dcfs", "load",
           "load_yaml"]

StartMode = Literal["all", "each", "none"]

_NETWORK_KEYS = {"start", "master_start", "reset_slaves", "nodes"}
_NODE_KEYS = {"id", "mandatory", "optional", "identity", "dcf", "heartbeat_ms",
              "boot_on_bootup", "keep_alive"}
_IDENTITY_KEYS = ("device_type", "vendor", "product", "revision", "serial")


class NetworkError(Error):
    """A network description that cannot be used; ``file`` and ``key`` say where."""

    def __init__(self, file: str, key: str | None, message: str, *,
                 located: bool = False) -> None:
        self.file = file
        self.key = key
        self.reason = message
        where = f"{file}: {key}: " if key else f"{file}: "
        super().__init__(message if located else where + message)

    @classmethod
    def from_eds(cls, exc: EdsError, file: str) -> NetworkError:
        """An EdsError of the DCF ``file`` (its first problem; it names its place)."""
        return cls(exc.file or file, exc.section, str(exc).splitlines()[0], located=True)


@dataclass(frozen=True)
class Identity:
    """What a slave must report: 0x1000 and 0x1018 sub1..4 (0 = not checked)."""

    device_type: int = 0
    vendor: int = 0
    product: int = 0
    revision: int = 0
    serial: int = 0


@dataclass(frozen=True)
class SlaveSpec:
    """One slave of the network."""

    node_id: int
    mandatory: bool = True
    identity: Identity = field(default_factory=Identity)
    config: bytes | None = None  # concise DCF, or None: nothing to download
    heartbeat_ms: int = 0
    boot_on_bootup: bool = True
    keep_alive: bool = False
    dcf: str | None = None  # the DCF the configuration came from (for messages)


@dataclass(frozen=True)
class Network:
    """The slaves and how the network starts."""

    slaves: tuple[SlaveSpec, ...]
    start: StartMode = "each"
    master_start: bool = True
    reset_slaves: bool = False
    source: str = "<network>"

    def slave(self, node_id: int) -> SlaveSpec | None:
        return next((s for s in self.slaves if s.node_id == node_id), None)


# ---------------------------------------------------------------------------------------
# YAML


def _describe(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


class _Reader:
    """Typed access to the parsed YAML, with errors naming file and key."""

    def __init__(self, file: str) -> None:
        self.file = file

    def fail(self, key: str | None, message: str) -> NetworkError:
        return NetworkError(self.file, key, message)

    def mapping(self, value: object, key: str | None, allowed: set[str] | tuple[str, ...]
                ) -> Mapping[str, Any]:
        if not isinstance(value, dict):
            raise self.fail(key, f"expected a mapping, got {_describe(value)}")
        for name in value:
            if name not in allowed:
                sub = f"{key}.{name}" if key else str(name)
                raise self.fail(sub, f"unknown key (known: {', '.join(sorted(allowed))})")
        return value

    def integer(self, value: object, key: str, low: int, high: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, f"expected an integer, got {_describe(value)}")
        if not low <= value <= high:
            raise self.fail(key, f"{value} is outside {low}..{high}")
        return value

    def boolean(self, value: object, key: str) -> bool:
        if not isinstance(value, bool):
            raise self.fail(key, f"expected true or false, got {_describe(value)}")
        return value


def load_yaml(text: str, file: str = "<yaml>", *, base: str | os.PathLike[str] = ".",
              node_id_of_master: int | None = None) -> Network:
    """A network from YAML ``text``; DCF paths are relative to ``base``."""
    import yaml  # noqa: PLC0415 -- loaded on first use

    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else None
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise NetworkError(file, where, f"not valid YAML: {problem}") from None
    r = _Reader(file)
    top = r.mapping(doc, None, _NETWORK_KEYS)
    start = top.get("start", "each")
    if start not in ("all", "each", "none"):
        raise r.fail("start", f"expected all, each or none, got {_describe(start)}")
    master_start = r.boolean(top.get("master_start", True), "master_start")
    reset_slaves = r.boolean(top.get("reset_slaves", False), "reset_slaves")
    nodes = top.get("nodes")
    if not isinstance(nodes, list) or not nodes:
        raise r.fail("nodes", "expected a list of at least one node")
    slaves: list[SlaveSpec] = []
    seen: dict[int, str] = {}
    for i, item in enumerate(nodes):
        spec = _slave(r, item, f"nodes[{i}]", Path(base))
        if spec.node_id in seen:
            raise r.fail(f"nodes[{i}].id", f"node {spec.node_id} is listed twice "
                                           f"(also {seen[spec.node_id]})")
        if spec.node_id == node_id_of_master:
            raise r.fail(f"nodes[{i}].id", f"node {spec.node_id} is the master itself")
        seen[spec.node_id] = f"nodes[{i}]"
        slaves.append(spec)
    return Network(tuple(slaves), start=start, master_start=master_start,
                   reset_slaves=reset_slaves, source=file)


def _slave(r: _Reader, item: object, key: str, base: Path) -> SlaveSpec:
    node = r.mapping(item, key, _NODE_KEYS)
    model: eds.ObjectDictionary | None = None
    dcf_path: str | None = None
    if "dcf" in node:
        if not isinstance(node["dcf"], str) or not node["dcf"]:
            raise r.fail(f"{key}.dcf", f"expected a file name, got {_describe(node['dcf'])}")
        dcf_path = str(base / node["dcf"])
        model = _parse_dcf(dcf_path, r, f"{key}.dcf")
    if "id" in node:
        node_id = r.integer(node["id"], f"{key}.id", 1, 127)
    elif model is not None and model.node_id is not None and 1 <= model.node_id <= 127:
        node_id = model.node_id
    else:
        raise r.fail(f"{key}.id", "missing (and no DCF NodeID to take it from)")
    if "mandatory" in node and "optional" in node:
        mandatory = r.boolean(node["mandatory"], f"{key}.mandatory")
        if mandatory == r.boolean(node["optional"], f"{key}.optional"):
            raise r.fail(f"{key}.optional", "contradicts mandatory")
    elif "optional" in node:
        mandatory = not r.boolean(node["optional"], f"{key}.optional")
    else:
        mandatory = r.boolean(node.get("mandatory", True), f"{key}.mandatory")
    if "identity" in node:
        ident = r.mapping(node["identity"], f"{key}.identity", _IDENTITY_KEYS)
        identity = Identity(**{name: r.integer(ident.get(name, 0), f"{key}.identity.{name}",
                                               0, 0xFFFFFFFF) for name in _IDENTITY_KEYS})
    elif model is not None:
        identity = identity_of(model)
    else:
        identity = Identity()
    config = None
    if model is not None:
        try:
            config = concise.build(concise.from_dcf(model))
        except EdsError as exc:
            raise r.fail(f"{key}.dcf", str(exc)) from None
    return SlaveSpec(
        node_id=node_id, mandatory=mandatory, identity=identity, config=config,
        heartbeat_ms=r.integer(node.get("heartbeat_ms", 0), f"{key}.heartbeat_ms", 0, 0xFFFF),
        boot_on_bootup=r.boolean(node.get("boot_on_bootup", True), f"{key}.boot_on_bootup"),
        keep_alive=r.boolean(node.get("keep_alive", False), f"{key}.keep_alive"),
        dcf=dcf_path)


def _parse_dcf(path: str, r: _Reader, key: str) -> eds.ObjectDictionary:
    try:
        return eds.parse(Path(path))
    except EdsError as exc:
        raise r.fail(key, str(exc).splitlines()[0]) from None


def identity_of(model: eds.ObjectDictionary) -> Identity:
    """The identity a DCF describes: 0x1000 and 0x1018 sub1..4 (ParameterValue, else
    DefaultValue; 0 where neither is a number)."""

    def value(index: int, sub: int) -> int:
        obj = model.objects.get(index)
        var = obj.subs.get(sub) if obj is not None else None
        if var is None:
            return 0
        v = var.value if var.value is not None else var.default
        return v if isinstance(v, int) and 0 <= v <= 0xFFFFFFFF else 0

    return Identity(value(0x1000, 0), value(0x1018, 1), value(0x1018, 2), value(0x1018, 3),
                    value(0x1018, 4))


def load(path: str | os.PathLike[str], *, node_id_of_master: int | None = None) -> Network:
    """A network from a YAML file."""
    file = os.fspath(path)
    try:
        text = Path(file).read_text(encoding="utf-8")
    except OSError as exc:
        raise NetworkError(file, None, f"cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise NetworkError(file, None, "not UTF-8 text") from None
    return load_yaml(text, file, base=Path(file).parent, node_id_of_master=node_id_of_master)


def from_dcfs(paths: Sequence[str | os.PathLike[str]], *, heartbeat_ms: int = 0,
              start: StartMode = "each", node_id_of_master: int | None = None) -> Network:
    """A network of one mandatory slave per DCF (see the module doc)."""
    if not paths:
        raise NetworkError("<dcf>", None, "no DCF given")
    slaves: list[SlaveSpec] = []
    seen: dict[int, str] = {}
    for path in paths:
        file = os.fspath(path)
        try:
            model = eds.parse(Path(file))
        except EdsError as exc:
            raise NetworkError.from_eds(exc, file) from None
        node_id = model.node_id
        if node_id is None or not 1 <= node_id <= 127:
            raise NetworkError(file, "[DeviceComissioning] NodeID",
                               "missing or outside 1..127: a DCF names its node")
        if node_id in seen:
            raise NetworkError(file, "[DeviceComissioning] NodeID",
                               f"node {node_id} is also {seen[node_id]}")
        if node_id == node_id_of_master:
            raise NetworkError(file, "[DeviceComissioning] NodeID",
                               f"node {node_id} is the master itself")
        seen[node_id] = file
        try:
            config = concise.build(concise.from_dcf(model))
        except EdsError as exc:
            raise NetworkError.from_eds(exc, file) from None
        slaves.append(SlaveSpec(node_id=node_id, identity=identity_of(model), config=config,
                                heartbeat_ms=heartbeat_ms, dcf=file))
    return Network(tuple(sorted(slaves, key=lambda s: s.node_id)), start=start,
                   source=", ".join(os.fspath(p) for p in paths))


def from_files(paths: Sequence[str | os.PathLike[str]], *,
               node_id_of_master: int | None = None) -> Network:
    """One YAML file, or DCF files (decided by the extension: .yaml/.yml)."""
    names = [os.fspath(p) for p in paths]
    yamls = [n for n in names if n.lower().endswith((".yaml", ".yml"))]
    if yamls:
        if len(names) != 1:
            raise NetworkError(yamls[0], None, "a YAML network description comes alone")
        return load(names[0], node_id_of_master=node_id_of_master)
    return from_dcfs(names, node_id_of_master=node_id_of_master)
