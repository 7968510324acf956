"""Reading scenario YAML defensively: a stricter ``yaml.SafeLoader``.

A scenario is a few kilobytes of hand-written YAML. Anything else is refused, each within a
fraction of a second and with a :class:`~cosim.scenario.schema.ScenarioError` naming the file (and, where
there is one, the key path):

* files over :data:`MAX_BYTES`, not regular files, binary or non-UTF-8 content (the one file
  reader, :mod:`pneumorail.files`);
* duplicate keys in a mapping (PyYAML silently keeps the last one), reported at their key path;
* nesting deeper than :data:`MAX_DEPTH`: refused by the scanner itself, at the bracket or
  indentation that goes too deep (PyYAML's scanner slows down quadratically with nested flow
  brackets, and its composer and constructor recurse: 5000 ``[`` took 10 s and ended in a
  ``RecursionError``);
* more than :data:`MAX_NODES` values: counted while composing (each alias counts as a value), so a
  long list stops after that many, and counted again on the composed graph with every alias
  expanded (an "alias bomb" expands exponentially), before anything is constructed;
* values PyYAML cannot construct (``2024-13-45`` as a date, ``!!int abc``, unknown tags).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, List, Sequence, Tuple

import yaml

from cosim.errors import ScenarioError
from pneumorail.files import read_text

#: Largest scenario or parameter file read [bytes]; the shipped ones are 1-4 kB.
MAX_BYTES = 256 * 1024
#: Deepest nesting of mappings and lists (the shipped scenarios use 4).
MAX_DEPTH = 32
#: Most values (scalars, lists, mappings) a document may hold, aliases counted as often as they
#: are referenced (the shipped scenarios have about 150, the vehicle parameter file 130). Reading
#: takes ~30 us a value: the limit keeps any document well within a second.
MAX_NODES = 10_000


class _Refused(yaml.YAMLError):
    """Raised from inside the loader: what was refused and where (a PyYAML mark)."""

    def __init__(self, reason: str, mark):
        self.reason, self.mark = reason, mark
        super().__init__(reason)


class StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses duplicate keys, deep nesting and too many values."""

    def __init__(self, stream):
        super().__init__(stream)
        self._nodes = 0

    # --- scanner: nesting depth, checked where it grows (flow brackets, block indentation)
    def _deeper(self, extra: int) -> None:
        if self.flow_level + len(self.indents) + extra > MAX_DEPTH:
            raise _Refused(f"nesting deeper than {MAX_DEPTH} levels: not a scenario", self.get_mark())

    def fetch_flow_collection_start(self, TokenClass):
        self._deeper(1)
        super().fetch_flow_collection_start(TokenClass)

    def add_indent(self, column):
        added = super().add_indent(column)
        if added:
            self._deeper(0)
        return added

    # --- composer: number of values
    def compose_node(self, parent, index):
        self._nodes += 1
        if self._nodes > MAX_NODES:
            raise _Refused(f"more than {MAX_NODES} values: not a scenario", self.peek_event().start_mark)
        return super().compose_node(parent, index)

    # --- constructor: duplicate keys that the node check cannot see (e.g. 1 and 1.0)
    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            try:
                first = seen.get(key)
            except TypeError:                     # unhashable: super() says so, with its mark
                continue
            if first is not None:
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r} (first at line {first + 1})", key_node.start_mark)
            seen[key] = key_node.start_mark.line
        return super().construct_mapping(node, deep=deep)


def _key_text(node) -> str:
    return str(node.value) if isinstance(node, yaml.ScalarNode) else f"<{node.tag.rsplit(':', 1)[-1]}>"


def _check_graph(root, file, where: Sequence[str]) -> None:
    """Duplicate keys (at their key path) and the expanded size of the composed node graph.
    Aliases make it a DAG whose expansion can be exponential; its size is counted with one visit
    per distinct node (memo). The depth is bounded by the scanner (:data:`MAX_DEPTH`)."""
    sizes = {}

    def size(node, path: List[str]) -> int:
        if id(node) not in sizes:
            if isinstance(node, yaml.MappingNode):
                seen = {}
                for key_node, _ in node.value:
                    if isinstance(key_node, yaml.ScalarNode):
                        ident = (key_node.tag, key_node.value)
                        if ident in seen:
                            raise ScenarioError(file, [*where, *path, key_node.value],
                                                f"duplicate key (first at line {seen[ident] + 1}, again at line "
                                                f"{key_node.start_mark.line + 1}): each key at most once")
                        seen[ident] = key_node.start_mark.line
                total = 1 + sum(size(k, path) + size(v, [*path, _key_text(k)]) for k, v in node.value)
            elif isinstance(node, yaml.SequenceNode):
                def item(i):
                    return [*path[:-1], f"{path[-1]}[{i}]"] if path else [f"[{i}]"]
                total = 1 + sum(size(v, item(i)) for i, v in enumerate(node.value))
            else:
                total = 1
            sizes[id(node)] = total
        return sizes[id(node)]

    if size(root, []) > MAX_NODES:
        raise ScenarioError(file, where, f"the document expands to more than {MAX_NODES} values (aliases *name "
                                         f"repeating anchors &name): not a scenario")


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
    except ScenarioError:
        raise
    except _Refused as exc:
        raise ScenarioError(file, where, f"{exc.reason} (line {exc.mark.line + 1})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ScenarioError(file, where, f"not valid YAML{at}: {getattr(exc, 'problem', None) or exc}") from None
    except (ValueError, TypeError, OverflowError) as exc:   # e.g. 2024-13-45 read as a date, !!int abc
        raise ScenarioError(file, where, f"not valid YAML: a value cannot be read ({exc})") from None
    except RecursionError:
        raise ScenarioError(file, where, "nesting too deep: not a scenario") from None


def read_yaml(path: Path) -> Tuple[Any, str]:
    """(data, text) of a YAML file, refusing what cannot be a scenario (module doc); the file is
    read by the project's one reader (:func:`pneumorail.files.read_text`)."""
    text = read_text(path, "scenario or parameter file (YAML)", MAX_BYTES, error=ScenarioError).text
    return parse_yaml(text, Path(path)), text
