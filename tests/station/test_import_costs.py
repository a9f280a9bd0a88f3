"""Issue 42.8: bad imports are refused before their cost grows with the file: the plain CSV's first row
from the first 64 KB, a JSON's keys counted while it parses, a YAML's aliases counted on the node graph
(each distinct node once) before anything is built. Costs are checked by counts, not by the clock."""

from __future__ import annotations

import json

import pytest

from handeye.base.errors import SessionError
from handeye.base.yaml_text import ALIAS_EXPANSION_BUDGET, expanded_size, parse_yaml


def _bomb(levels: int = 9) -> str:
    """A few hundred bytes of YAML whose aliases expand to 9**levels values."""
    names = "abcdefghijkl"
    text = "a: &a [x, x, x, x, x, x, x, x, x]\n"
    for k in range(1, levels):
        text += f"{names[k]}: &{names[k]} [" + ", ".join([f"*{names[k - 1]}"] * 9) + "]\n"
    return text


def test_an_alias_bomb_is_refused_from_its_node_graph():
    import yaml

    text = _bomb()
    assert len(text) < 500
    with pytest.raises(SessionError, match="aliases expand the document beyond"):
        parse_yaml(text, "bomb.yaml")
    size, visited = expanded_size(yaml.compose(text, Loader=yaml.SafeLoader), 10**12)
    assert size > 9**8 and visited < 200  # counted without expanding: each distinct node once
    shared = "base: &b {x: 1, y: 2}\n" + "".join(f"p{k}: *b\n" for k in range(100))  # ordinary anchors load
    assert parse_yaml(shared, "ok.yaml")["p99"] == {"x": 1, "y": 2}
    assert 100 * 5 < ALIAS_EXPANSION_BUDGET


def test_a_plain_csv_without_a_header_is_refused_from_its_head(tmp_path, monkeypatch):
    from handeye.station.importers import plain, read_any

    monkeypatch.setattr(plain, "read_text", lambda path: pytest.fail("the whole file was read"))
    one_line = tmp_path / "one.csv"
    one_line.write_text(",".join(["1.5"] * 300_000))  # 1.2 MB on one line
    with pytest.raises(SessionError, match="line 1 is longer than 64 KB"):
        read_any(one_line, format="plain")
    numbers = tmp_path / "numbers.csv"
    numbers.write_text("# poses\n" + "\n".join(",".join(["1.5"] * 15) for _ in range(20000)))
    with pytest.raises(SessionError, match="line 2: expected a header row"):
        read_any(numbers, format="plain")


def test_a_json_of_too_many_keys_is_refused_while_it_parses(tmp_path, monkeypatch):
    from handeye.station.importers import common

    seen = []
    original = common._object_without_duplicates
    monkeypatch.setattr(common, "_object_without_duplicates", lambda pairs: seen.append(1) or original(pairs))
    text = json.dumps([{"k": i} for i in range(3 * common.MAX_JSON_KEYS)])
    with pytest.raises(SessionError, match=f"over {common.MAX_JSON_KEYS} keys"):
        common.parse_json(text, "keys.json")
    assert len(seen) <= common.MAX_JSON_KEYS  # stopped at the bound, a third of the way in
    assert common.parse_json(json.dumps([{"k": i} for i in range(1000)]), "ok.json")[999] == {"k": 999}
