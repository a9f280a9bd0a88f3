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


def test_a_json_of_too_many_keys_in_one_object_is_refused_before_it_parses(tmp_path, monkeypatch):
    # issue 42 (d): the hook counts an object's keys only once the whole object is parsed (its pairs all
    # built: a flat 1M-key object cost ~4 s / 524 MB); the keys are now counted on the text, no parse
    from handeye.station.importers import common, read_any

    monkeypatch.setattr(common.json, "loads", lambda *a, **k: pytest.fail("the JSON was parsed"))
    path = tmp_path / "flat.json"
    path.write_text(json.dumps({f"key{i}": i for i in range(common.MAX_JSON_KEYS + 1)}))
    with pytest.raises(SessionError, match=f"over {common.MAX_JSON_KEYS} keys"):
        read_any(path)


def test_the_key_count_on_the_text_counts_keys_not_colons():
    from handeye.station.importers.common import MAX_JSON_KEYS, _more_keys_than, parse_json

    bound = 3
    assert _more_keys_than('{"a:b": "c\\\\\\":", "x": [1, {"y": "z:", "w": ":"}]}', bound)  # 4 keys
    assert not _more_keys_than('{"a:b": "c\\\\\\"::", "x": [1, {"y": "z:::"}]}', bound)  # 3 keys, 9 colons
    times = json.dumps({"stamps": [f"12:{i % 60:02d}:00" for i in range(MAX_JSON_KEYS)]})  # 400000 colons, 1 key
    assert not _more_keys_than(times, MAX_JSON_KEYS) and len(parse_json(times, "t.json")["stamps"]) == MAX_JSON_KEYS
    keys = json.dumps([{"k": i} for i in range(MAX_JSON_KEYS + 1)])
    assert _more_keys_than(keys, MAX_JSON_KEYS) and not _more_keys_than(keys, MAX_JSON_KEYS + 1)
