"""Mitsuba 3 XML scene files as scene dicts: :func:`read_xml`.

The file's objects (``shape``, ``bsdf``, ``emitter``, ``sensor``, ``film``,
``sampler``, ``rfilter``, ``integrator``, ``texture``) become nested dicts
as ``mi.load_dict`` takes them, keyed by their ``name`` attribute, else by
their tag (``"bsdf"``, ``"emitter"``, ``"film"``, ...; top-level objects by
their ``id``, else ``"<tag>_<n>"``); properties (``float``, ``integer``,
``boolean``, ``string``, ``rgb``, ``spectrum`` (one value), ``point``,
``vector``) become values; ``<transform>`` (``translate``, ``rotate``, ``scale``,
``matrix``, ``lookat``, applied in order) a 4x4 matrix; ``<ref id=...>`` a
``{"type": "ref", "id": ...}`` (keyed by its name, else by the referenced
object's tag); a ``filename`` string is taken relative to the main file's
folder (as Mitsuba's file resolver, also in an included file). ``<default name=... value=...>`` and
``$name`` substitute parameters (given ones win, as in ``mi.load_file(path,
name=value)``), and ``<include filename=...>`` reads another file (relative
to the including one) in place. Errors name the file and line.
"""

from __future__ import annotations

import math
import os
import re
import xml.parsers.expat
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._core import Frame

__all__ = ["read_xml"]

#: Tags of objects with a ``type``: nested dicts.
OBJECTS = {"shape", "bsdf", "emitter", "sensor", "film", "sampler", "rfilter",
           "integrator", "texture", "medium", "phase", "volume"}
#: Tags of property values.
PROPERTIES = {"float", "integer", "boolean", "string", "rgb", "spectrum", "point", "vector",
              "transform"}


@dataclass
class _Element:
    tag: str
    attrs: dict[str, str]
    file: str
    line: int
    children: list["_Element"] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"{self.file}:{self.line}"

    def error(self, message: str) -> ValueError:
        return ValueError(f"{self.where}: <{self.tag}>: {message}")

    def attr(self, name: str) -> str:
        if name not in self.attrs:
            raise self.error(f"needs the attribute {name!r}")
        return self.attrs[name]


def _parse(path: str) -> _Element:
    """The element tree of ``path``, each element with its line."""
    with open(path, "rb") as f:
        data = f.read()
    parser = xml.parsers.expat.ParserCreate()
    root: list[_Element] = []
    stack: list[_Element] = []

    def start(tag: str, attrs: dict[str, str]) -> None:
        e = _Element(tag, attrs, path, parser.CurrentLineNumber)
        (stack[-1].children if stack else root).append(e)
        stack.append(e)

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: stack.pop()
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError as e:
        raise ValueError(f"{path}:{e.lineno}: not well-formed XML: "
                         f"{xml.parsers.expat.ErrorString(e.code)}") from None
    return root[0]


_NUMBER_SPLIT = re.compile(r"[,\s]+")


def _numbers(e: _Element, text: str, count: tuple[int, ...]) -> list[float]:
    """The numbers of ``text`` (separated by spaces or commas), as many as
    one of ``count``."""
    parts = [p for p in _NUMBER_SPLIT.split(text.strip()) if p]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise e.error(f"{text!r} is not a list of numbers") from None
    if len(values) not in count:
        raise e.error(f"{text!r}: needs {' or '.join(map(str, count))} numbers")
    if not all(math.isfinite(v) for v in values):
        raise e.error(f"{text!r}: the numbers must be finite")
    return values


def _xyz(e: _Element, default: float) -> list[float]:
    """``value="x y z"``, or the attributes x, y, z (each defaulting)."""
    if "value" in e.attrs:
        v = _numbers(e, e.attrs["value"], (1, 3))
        return v * 3 if len(v) == 1 else v
    return [float(_numbers(e, e.attrs.get(k, str(default)), (1,))[0]) for k in "xyz"]


def _rotation(axis: np.ndarray, degrees: float) -> np.ndarray:
    """Mitsuba's rotation by ``degrees`` about ``axis``, 4x4:
    ``cos·I + sin·[a]× + (1 − cos)·a aᵀ`` with the axis as given (Mitsuba
    does not normalise it)."""
    a = np.asarray(axis, dtype=np.float64)
    t = math.radians(degrees)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    m = np.eye(4)
    m[:3, :3] = math.cos(t) * np.eye(3) + math.sin(t) * k + (1 - math.cos(t)) * np.outer(a, a)
    return m


def _up(direction: np.ndarray) -> np.ndarray:
    """Mitsuba's ``up`` when a ``lookat`` gives none: the first tangent of
    the orthonormal basis around the viewing direction (mcsample's
    :class:`Frame` is built the same way)."""
    return np.asarray(Frame(direction / np.linalg.norm(direction)).s, dtype=np.float64)


def _transform(e: _Element) -> np.ndarray:
    """The matrix of a ``<transform>``: each child applied after the ones
    before it (left-multiplied)."""
    from .parse import look_at

    m = np.eye(4)
    for op in e.children:
        step = np.eye(4)
        if op.tag == "translate":
            step[:3, 3] = _xyz(op, 0.0)
        elif op.tag == "scale":
            step[:3, :3] = np.diag(_xyz(op, 1.0))
        elif op.tag == "rotate":
            axis = np.array(_numbers(op, op.attrs["value"], (3,)) if "value" in op.attrs
                            else _xyz(op, 0.0))
            step = _rotation(axis, _numbers(op, op.attr("angle"), (1,))[0])
        elif op.tag == "matrix":
            values = _numbers(op, op.attr("value"), (9, 16))
            if len(values) == 9:
                step[:3, :3] = np.reshape(values, (3, 3))
            else:
                step = np.reshape(values, (4, 4))
        elif op.tag == "lookat":
            origin, target = (np.array(_numbers(op, op.attr(k), (3,))) for k in ("origin", "target"))
            try:
                up = (np.array(_numbers(op, op.attrs["up"], (3,))) if "up" in op.attrs
                      else _up(target - origin))
                step = look_at(origin, target, up)
            except (ValueError, ZeroDivisionError) as err:
                raise op.error(str(err) or "origin and target must differ") from None
        else:
            raise op.error("not a transform operation (translate, rotate, scale, "
                           "matrix, lookat)")
        m = step @ m
    if not abs(np.linalg.det(m[:3, :3])) > 0:
        raise e.error("the transform is singular")
    return m


def _value(e: _Element) -> Any:
    """The value of a property element."""
    if e.tag == "transform":
        return _transform(e)
    if e.tag in ("point", "vector"):
        if "value" in e.attrs:
            return _numbers(e, e.attrs["value"], (3,))
        return _xyz(e, 0.0)
    text = e.attr("value")
    if e.tag == "float":
        return _numbers(e, text, (1,))[0]
    if e.tag == "integer":
        try:
            return int(text)
        except ValueError:
            raise e.error(f"value = {text!r} is not an integer") from None
    if e.tag == "boolean":
        if text.lower() not in ("true", "false"):
            raise e.error(f"value = {text!r}: must be true or false")
        return text.lower() == "true"
    if e.tag == "string":
        return text
    if e.tag == "spectrum":
        # One value: a constant spectrum (Mitsuba's sampled spectra,
        # "wavelength:value" pairs, are not read).
        return {"type": "spectrum", "value": _numbers(e, text, (1,))[0]}
    if e.tag == "rgb":
        v = _numbers(e, text, (1, 3))
        return {"type": "rgb", "value": v * 3 if len(v) == 1 else v}
    raise AssertionError(e.tag)  # PROPERTIES holds no other tag


class _Reader:
    """Turns elements into dict entries, with the parameters in force and
    the files being read (to refuse a cyclic include)."""

    def __init__(self, parameters: dict[str, str]) -> None:
        self.parameters = dict(parameters)
        self.reading: list[str] = []
        #: Where each top-level entry was read ("file:line").
        self.where: dict[str, str] = {}
        #: The tag of each object with an id, so that an unnamed <ref> to
        #: a bsdf is the referrer's "bsdf".
        self.tags: dict[str, str] = {}
        #: Unnamed <ref>s: their placeholder key, the dict holding them and
        #: the element, renamed by :meth:`resolve` once every id is known.
        self.refs: list[tuple[str, dict[str, Any], _Element]] = []
        #: The main scene file's folder: file names are relative to it.
        self.folder = ""

    def pending(self, e: _Element) -> str:
        """A placeholder key for the unnamed reference ``e``."""
        return f"\0ref{len(self.refs)}"

    def resolve(self) -> None:
        """Keys each unnamed reference by the tag of the object it names."""
        for placeholder, entries, e in self.refs:
            target = entries[placeholder]["id"]
            if target not in self.tags:
                raise e.error(f"no object with id {target!r} in the scene")
            key = self.tags[target]
            if key in entries:
                raise e.error(f"a second {key!r} in the same object")
            entries[key] = entries.pop(placeholder)

    def substitute(self, e: _Element) -> None:
        def replace(match: re.Match[str]) -> str:
            name = match.group(1)
            if name not in self.parameters:
                raise e.error(f"${name} is not a parameter (give it to the call or in "
                              "a <default>)")
            return self.parameters[name]

        e.attrs = {k: re.sub(r"\$(\w+)", replace, v) for k, v in e.attrs.items()}

    def read_file(self, path: str, origin: _Element | None) -> list[_Element]:
        """The children of the ``<scene>`` in ``path``."""
        path = os.path.abspath(path)
        if path in self.reading:
            chain = " -> ".join(self.reading + [path])
            raise (origin.error if origin else ValueError)(f"cyclic <include>: {chain}")
        if not os.path.exists(path):
            message = f"no such file: {path}"
            if origin is None:
                raise FileNotFoundError(message)
            raise FileNotFoundError(f"{origin.where}: <include>: {message}")
        root = _parse(path)
        if root.tag != "scene":
            raise root.error("the file's root element must be <scene>")
        return root.children

    def fill(self, entries: dict[str, Any], children: list[_Element], top: bool,
             counts: dict[str, int] | None = None) -> None:
        """Adds the entries of ``children`` to ``entries``; ``counts``: the
        objects of each tag so far (shared with the files it includes)."""
        counts = {} if counts is None else counts
        for e in children:
            self.substitute(e)
            if e.tag == "default":
                self.parameters.setdefault(e.attr("name"), e.attr("value"))
            elif e.tag == "include":
                path = os.path.join(os.path.dirname(e.file), e.attr("filename"))
                included = self.read_file(path, e)
                self.reading.append(os.path.abspath(path))
                self.fill(entries, included, top, counts)
                self.reading.pop()
            elif e.tag in PROPERTIES:
                name = e.attr("name")
                for op in e.children:  # a transform's steps
                    self.substitute(op)
                value = _value(e)
                if e.tag == "string" and name == "filename":
                    # Relative to the main scene file's folder, as Mitsuba's
                    # file resolver (also from an included file).
                    value = os.path.join(self.folder, value)
                entries[name] = value
                if top:
                    self.where[name] = e.where
            elif e.tag == "ref":
                # Unnamed: keyed by the referenced object's tag, known when
                # the whole file is read (a reference may come first).
                key = e.attrs.get("name") or self.pending(e)
                entries[key] = {"type": "ref", "id": e.attr("id")}
                if "name" not in e.attrs:
                    self.refs.append((key, entries, e))
            elif e.tag in OBJECTS:
                obj: dict[str, Any] = {"type": e.attr("type")}
                if "id" in e.attrs:
                    obj["id"] = e.attrs["id"]
                    self.tags[e.attrs["id"]] = e.tag
                self.fill(obj, e.children, top=False)
                counts[e.tag] = counts.get(e.tag, 0) + 1
                if "name" in e.attrs:
                    key = e.attrs["name"]
                elif top:
                    key = e.attrs.get("id", f"{e.tag}_{counts[e.tag]}")
                else:  # "bsdf", then "bsdf_2", ... as nested objects come
                    key = e.tag if counts[e.tag] == 1 else f"{e.tag}_{counts[e.tag]}"
                if key in entries:
                    raise e.error(f"a second {key!r} in the same object")
                entries[key] = obj
                if top:
                    self.where[key] = e.where
            else:
                raise e.error("not a tag of Mitsuba 3's scene format")


def read_xml(path: str | os.PathLike[str], **parameters: Any) -> dict[str, Any]:
    """The scene dict of a Mitsuba 3 XML file.

    Parameters
    ----------
    path : str or path-like
        The scene file.
    **parameters
        Values for the file's ``$name`` parameters (they override its
        ``<default>`` elements), as ``mi.load_file`` takes them.

    Returns
    -------
    dict ``{"type": "scene", ...}`` for :meth:`mcsample.Scene.from_mitsuba`
    (or for ``mi.load_dict``, apart from the transforms, which are 4x4
    numpy arrays).

    Raises OSError when a file cannot be read, ValueError naming the file and
    line of anything that is not well-formed (a missing parameter, a cyclic
    include, a singular transform, a tag outside Mitsuba's format).
    """
    return read_xml_located(path, **parameters)[0]


def read_xml_located(path: str | os.PathLike[str], **parameters: Any
                     ) -> tuple[dict[str, Any], dict[str, str]]:
    """:func:`read_xml`, and where each top-level entry was read: its key →
    ``"file:line"``."""
    reader = _Reader({k: str(v).lower() if isinstance(v, bool) else str(v)
                      for k, v in parameters.items()})
    path = os.fspath(path)
    children = reader.read_file(path, None)
    reader.reading.append(os.path.abspath(path))
    reader.folder = os.path.dirname(os.path.abspath(path))
    scene: dict[str, Any] = {"type": "scene"}
    reader.fill(scene, children, top=True)
    reader.resolve()
    return scene, reader.where
