"""The HTML building blocks of the calibration report: its inline CSS, footer, escaping, embedded
PNGs (base64 ``data:`` URIs: no links to other files or the network) and key-value grids."""

from __future__ import annotations

import base64
import html
from collections.abc import Iterable

__all__ = ["CSS", "FOOTER", "escape", "img", "num", "kv"]


CSS = """
body{font-family:"Segoe UI",Arial,Helvetica,sans-serif;margin:0;background:#f3f4f6;color:#1b1b1b;font-size:15px}
main{max-width:1280px;margin:0 auto;padding:18px 24px 40px}
h1{font-size:24px;margin:6px 0 2px} h2{font-size:19px;margin:28px 0 8px;border-bottom:2px solid #d5d8dc;padding-bottom:4px}
.sub{color:#555;font-size:13px;margin-bottom:14px}
section{background:#fff;border-radius:6px;padding:12px 18px 16px;margin-bottom:16px;box-shadow:0 1px 2px rgba(0,0,0,.08)}
.verdict{font-size:44px;font-weight:800;letter-spacing:2px;padding:10px 20px;border-radius:6px;color:#fff;display:inline-block}
.pass{background:#2e7d32} .fail{background:#c62828} .none{background:#757575}
.verdict-line{font-size:15px;margin:8px 0 4px}
.grid{display:grid;grid-template-columns:repeat(auto-fit,minmax(330px,1fr));gap:6px 28px;margin-top:12px}
.kv{display:grid;grid-template-columns:170px 1fr;gap:3px 10px;align-items:baseline;align-content:start}
.kv div:nth-child(odd){color:#555}
code,.literal{font-family:Consolas,"DejaVu Sans Mono",monospace}
.literal{background:#f0f3f7;border:1px solid #ccd3dc;border-radius:4px;padding:8px 10px;font-size:16px;
 display:block;margin:4px 0 10px;word-break:break-all;user-select:all}
table{border-collapse:collapse;width:100%;font-size:14px;margin:6px 0}
th,td{border-bottom:1px solid #e1e4e8;padding:5px 8px;text-align:left;vertical-align:top}
th{background:#f6f7f9;font-weight:600} td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
tr.bad td{background:#fdecea} tr.chosen td{background:#e8f0fb;font-weight:600}
.ok{color:#2e7d32;font-weight:700} .ko{color:#c62828;font-weight:700}
img{max-width:100%;height:auto;display:block;margin:8px auto}
.how{color:#444;font-size:13.5px;margin:4px 0}
.note{color:#555;font-size:13px}
ul{margin:4px 0 4px 20px;padding:0}
footer{color:#666;font-size:12.5px;margin-top:18px}
.origin{background:#6a1b9a;color:#fff;font-size:18px;padding:10px 16px;border-radius:6px;margin:0 0 12px}
.origin b{font-size:22px;letter-spacing:1px}
.donotwrite{border:3px solid #c62828;border-radius:6px;padding:6px 12px 8px;margin:10px 0;background:#f5f5f5}
.donotwrite-banner{color:#c62828;font-weight:800;font-size:18px;margin:2px 0 6px}
.void{display:block;color:#9e9e9e;font-family:Consolas,"DejaVu Sans Mono",monospace;font-size:16px;
 text-decoration:line-through;background:#ececec;border:1px dashed #bdbdbd;border-radius:4px;padding:8px 10px;
 margin:4px 0 10px;word-break:break-all;user-select:none;-webkit-user-select:none}
"""


def escape(text: object) -> str:
    return html.escape(str(text), quote=True)


def img(png: bytes, alt: str) -> str:
    return f'<img alt="{escape(alt)}" src="data:image/png;base64,{base64.b64encode(png).decode("ascii")}">'


def num(value: float | None, fmt: str = "{:.3f}") -> str:
    return "n/a" if value is None else fmt.format(value)


def kv(pairs: Iterable[tuple[object, object]]) -> str:
    return '<div class="kv">' + "".join(f"<div>{escape(k)}</div><div>{v}</div>" for k, v in pairs) + "</div>"


FOOTER = (
    "<footer>Units: mm and degrees; quaternions q1..q4 = (w, x, y, z), scalar first. The camera frame is the left "
    "camera of the stereo head (x right, y down, z forward). Uncertainties are one sigma from the "
    "estimator's covariance (random errors); the cross-validated accuracy also shows systematic ones. Report "
    "written by handeye.</footer>")
