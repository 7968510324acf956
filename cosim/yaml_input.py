"""Reading scenario YAML defensively: a stricter ``yaml.SafeLoader``.

A scenario is a few kilobytes of hand-written YAML. Anything else is refused, each within a
fraction of a second and with a :class:`~cosim.schema.ScenarioError` naming the file:

* files over :data:`MAX_BYTES`, binary or non-UTF-8 content;
* duplicate keys in a mapping (PyYAML silently keeps the last one);
* nesting deeper than :data:`MAX_DEPTH` (PyYAML's recursive constructor would overflow the
  stack) and documents that expand to more than :data:`MAX_NODES` values (an "alias bomb"
  expands exponentially): both are checked on the composed node graph, before anything is
  constructed.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence, Tuple

import yaml

from .schema import ScenarioError

#: Largest scenario or parameter file read [bytes]; the shipped ones are 1-3 kB.
MAX_BYTES = 1 << 20
#: Deepest nesting of mappings and lists (the shipped scenarios use 4).
MAX_DEPTH = 32
#: Most values (scalars, lists, mappings) a document may expand to, aliases counted as often as
#: they are referenced (the shipped scenarios have about 150).
MAX_NODES = 100_000


class StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses duplicate keys."""

    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r} (first at line {seen[key] + 1})", key_node.start_mark)
            seen[key] = key_node.start_mark.line
        return super().construct_mapping(node, deep=deep)


def _check_graph(root, file, where: Sequence[str]) -> None:
    """Nesting depth and expanded size of the composed node graph. Aliases make it a DAG whose
    expansion can be exponential; its size is counted with one visit per distinct node (memo),
    and the recursion is bounded by the depth check."""
    sizes = {}

    def size(node, depth: int) -> int:
        if depth > MAX_DEPTH:
            raise ScenarioError(file, where, f"nesting deeper than {MAX_DEPTH} levels "
                                             f"(line {node.start_mark.line + 1}): not a scenario")
        if id(node) not in sizes:
            children = ([n for pair in node.value for n in pair] if isinstance(node, yaml.MappingNode) else
                        node.value if isinstance(node, yaml.SequenceNode) else [])
            sizes[id(node)] = 1 + sum(size(c, depth + 1) for c in children)
        return sizes[id(node)]

    if size(root, 1) > MAX_NODES:
        raise ScenarioError(file, where, f"the document expands to more than {MAX_NODES} values (aliases *name "
                                         f"repeating aliases): not a scenario")


def parse_yaml(text: str, file, where: Sequence[str] = ()) -> Any:
    """The data of one YAML document, strictly (module doc); errors name ``file`` and ``where``."""
    try:
        loader = StrictLoader(text)
        try:
            root = loader.get_single_node()
            if root is None:
                return None
            _check_graph(root, file, where)
            return loader.construct_document(root)
        finally:
            loader.dispose()
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ScenarioError(file, where, f"not valid YAML{at}: {getattr(exc, 'problem', None) or exc}") from None
    except RecursionError:
        raise ScenarioError(file, where, "nesting too deep: not a scenario") from None


def read_yaml(path: Path) -> Tuple[Any, str]:
    """(data, text) of a YAML file, refusing what cannot be a scenario (module doc)."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise ScenarioError(path, [], f"the file is {size / 1e6:.1f} MB; a scenario is at most "
                                          f"{MAX_BYTES // 1024} kB of YAML")
        raw = path.read_bytes()
    except OSError as exc:
        raise ScenarioError(path, [], f"cannot read the file ({exc.strerror})") from None
    if b"\0" in raw:
        raise ScenarioError(path, [], "binary content (NUL bytes): expected a YAML text file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ScenarioError(path, [], f"not UTF-8 text (byte {exc.start}): expected a YAML text file") from None
    return parse_yaml(text, path), text
