"""report.html of one run: the scene, its parameters, the results as tables, every chart,
wall time and machine, links to the data files.

usage: report.py <output folder> [<run record as JSON>]

The page is static and self-contained: charts are embedded as data: URIs, the style sheet is
inline, nothing is fetched from a network, and it reads on a phone (viewport, tables scroll
sideways). Standard library only, so a report is written even where matplotlib is missing.
The file is written under a temporary name and renamed, so it is whole or absent.
"""
import base64
import html
import json
import math
import os
import re
import sys

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0 auto;
 max-width:1100px;padding:0.8em;line-height:1.4;color:#1d1d1f;background:#fff}
h1{font-size:1.5em;margin:0.2em 0}h2{font-size:1.2em;margin-top:1.6em;
 border-bottom:1px solid #ddd}h3{font-size:1.05em}
.status{padding:0.5em 0.8em;border-radius:6px;margin:0.6em 0}
.complete{background:#e6f4ea}.stopped,.running{background:#fff4d6}.failed{background:#fde7e7}
.scroll{overflow-x:auto;-webkit-overflow-scrolling:touch}
table{border-collapse:collapse;margin:0.4em 0;font-size:0.9em}
th,td{border:1px solid #ddd;padding:0.25em 0.5em;text-align:left;vertical-align:top}
th{background:#f4f4f6}td.num{text-align:right;font-variant-numeric:tabular-nums;
 white-space:nowrap}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}
figcaption{font-size:0.85em;color:#555}code{font-size:0.95em}
ul.files li{margin:0.2em 0}.muted{color:#666;font-size:0.9em}
"""

# Units of the engine's scene files "mm, us, ug": force N, stress N/mm^2 = MPa.
MM_US_UG = {
    "length": "mm", "time": "µs", "mass": "µg", "force": "N", "stress": "MPa",
    "speed": "mm/µs", "density": "kg/m³", "energy": "mJ", "stiffness": "N/mm",
    "rate": "1/µs", "frequency": "MHz", "spin": "rad/µs",
}

# (pattern on the last part of a key, dimension or literal unit); the first match wins.
# Literal units start with "=": they hold whatever the scene's unit system is. Overlaps are
# left without a unit: scenes report them as lengths or as fractions of a radius.
UNIT_RULES = [
    (r"(^|_)wall_(time_)?s(econds)?$|^wall_time_s$|^seconds$", "=s"),
    (r"_deg$|^angle", "=deg"),
    (r"_per_second$", "=1/s"),
    (r"(^|_)(steps?|count|particles|builds|contacts|samples|frames|variants|stages)$", "=–"),
    (r"_star(_|$)|_over_|_ratio|ratio_|fraction|^phi|_phi$|^z$|^z_|_z$|restitution|friction"
     r"|^mu$|^e_|^chi|^alpha|^zeta|^rho_star|error|spread|^strain|_strain$|poisson|_number$",
     "=–"),
    (r"overlap", "="),
    (r"stress|pressure|sigma|modul|^[KGM]_|^[KGM]$|_(K|G|M)$|^M_probe|young|shear_mod", "stress"),
    (r"force", "force"),
    (r"speed|velocity|^v_?p|^vp|^v$|_v$", "speed"),
    (r"spin", "spin"),
    (r"frequency|^f_|_freq|fdom|^f$", "frequency"),
    (r"density|^rho", "density"),
    (r"energy|^ekin|^epot|^e_kin|^e_pot", "energy"),
    (r"^kn$|^kt$|stiffness", "stiffness"),
    (r"time|duration|^t_|^dt$|_dt$", "time"),
    (r"^gap$|length|radius|diameter|height|distance", "length"),
    (r"mass", "mass"),
]


def scene_units(scene_file):
    """The unit system a scene file declares in its comments ("Units: mm, us, ug")."""
    try:
        with open(scene_file, encoding="utf-8") as f:
            text = f.read()
    except OSError:
        return None, {}
    for line in text.splitlines():
        if "Units:" in line and re.search(r"\bmm\b", line) and re.search(r"\bus\b", line):
            return line.split("Units:", 1)[1].strip(), MM_US_UG
    return None, {}


def scene_comments(scene_file):
    """section.key -> the comment after its value in the scene file (often the unit)."""
    notes = {}
    try:
        with open(scene_file, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError:
        return notes
    section = ""
    for line in lines:
        s = line.strip()
        m = re.match(r"^\[([^\]]+)\]", s)
        if m:
            section = m.group(1).strip()
            continue
        m = re.match(r'^([A-Za-z0-9_."-]+)\s*=\s*(.*?)\s+#\s*(.+)$', s)
        if m and m.group(2).count('"') % 2 == 0:
            key = m.group(1).strip('"')
            notes[(section + "." if section else "") + key] = m.group(3).strip()
    return notes


def unit_of(key, system):
    last = key.split(".")[-1].split("/")[-1]
    last = re.sub(r"_(final|initial|start|end|mean|max|min|fit)$", "", last)
    for pattern, dim in UNIT_RULES:
        if re.search(pattern, last):
            if dim.startswith("="):
                return dim[1:]
            return system.get(dim, "")
    return ""


def is_scalar(v):
    return v is None or isinstance(v, (bool, int, float, str))


def fmt(v, whole=False):
    """A value as text; long lists of numbers are summarised unless `whole` (parameters are
    shown as given)."""
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v) or math.isinf(v):
            return str(v)
        if v == int(v) and abs(v) < 1e15:
            return str(int(v))
        return "%.6g" % v
    if isinstance(v, str):
        return v
    if isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                   for x in v):
        if len(v) <= 8 or (whole and len(v) <= 200):
            return "[" + ", ".join(fmt(x) for x in v) + "]"
        return "%d values, %s … %s" % (len(v), fmt(min(v)), fmt(max(v)))
    text = json.dumps(v)
    return text if len(text) <= 200 else text[:200] + " …"


def cell(v, whole=False):
    cls = ' class="num"' if isinstance(v, (int, float)) and not isinstance(v, bool) else ""
    return "<td%s>%s</td>" % (cls, html.escape(fmt(v, whole)))


def table(header, rows):
    out = ['<div class="scroll"><table><thead><tr>']
    out += ["<th>%s</th>" % html.escape(h) for h in header]
    out.append("</tr></thead><tbody>")
    for r in rows:
        out.append("<tr>" + "".join(r) + "</tr>")
    out.append("</tbody></table></div>")
    return "".join(out)


def flatten(obj, prefix=""):
    """Nested objects of scalars -> dotted keys; lists of numbers stay as values."""
    flat = []
    for k, v in obj.items():
        key = prefix + k
        if isinstance(v, dict):
            flat += flatten(v, key + ".")
        else:
            flat.append((key, v))
    return flat


def key_value_table(pairs, system):
    rows = [["<td><code>%s</code></td>" % html.escape(k), cell(v),
             "<td>%s</td>" % html.escape(unit_of(k, system))] for k, v in pairs]
    return table(["quantity", "value", "unit"], rows)


def row_table(rows_in, system, labels=None):
    """A list of objects (one per configuration, speed, model ...) as one table; `labels`
    names the rows (the keys of an object of objects)."""
    columns = []
    flat_rows = []
    for r in rows_in:
        pairs = flatten(r) if isinstance(r, dict) else [("value", r)]
        flat_rows.append(dict(pairs))
        for k, _ in pairs:
            if k not in columns:
                columns.append(k)
    header = ([""] if labels else []) + [
        c + (" [%s]" % unit_of(c, system) if unit_of(c, system) not in ("", "–") else "")
        for c in columns]
    rows = []
    for i, r in enumerate(flat_rows):
        lead = ["<th>%s</th>" % html.escape(str(labels[i]))] if labels else []
        rows.append(lead + [cell(r.get(c)) for c in columns])
    return table(header, rows)


def results_html(summary, system):
    """Every member of summary.json but the scene, its file, its parameters and the run."""
    skip = {"scene", "scene_file", "parameters", "run"}
    scalars, sections = [], []
    for k, v in summary.items():
        if k in skip:
            continue
        if is_scalar(v) or (isinstance(v, list) and all(is_scalar(x) for x in v)):
            scalars.append((k, v))
        elif isinstance(v, list) and all(isinstance(x, dict) for x in v):
            sections.append("<h3>%s</h3>%s" % (html.escape(k), row_table(v, system)))
        elif isinstance(v, dict):
            subs = list(v.values())
            if subs and all(isinstance(x, dict) for x in subs):
                sections.append("<h3>%s</h3>%s" % (html.escape(k),
                                                   row_table(subs, system, list(v.keys()))))
            else:
                sections.append("<h3>%s</h3>%s" % (html.escape(k),
                                                   key_value_table(flatten(v), system)))
        else:
            sections.append("<h3>%s</h3><pre>%s</pre>" % (html.escape(k),
                                                          html.escape(json.dumps(v, indent=1))))
    out = []
    if scalars:
        out.append(key_value_table(scalars, system))
    return "".join(out + sections)


def size_text(n):
    for unit in ("B", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return ("%d %s" % (n, unit)) if unit == "B" else ("%.1f %s" % (n, unit))
        n /= 1024.0
    return str(n)


def main(argv):
    if len(argv) < 2:
        sys.exit("usage: report.py <output folder> [<run record as JSON>]")
    out = argv[1]
    run = json.loads(argv[2]) if len(argv) > 2 and argv[2] else None
    summary = None
    try:
        with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
            summary = json.load(f)
    except (OSError, ValueError):
        pass
    if run is None and summary is not None:
        run = summary.get("run")
    run = run or {}
    scene = (summary or {}).get("scene") or run.get("scene") or os.path.basename(
        os.path.abspath(out))
    scene_file = (summary or {}).get("scene_file") or run.get("scene_file", "")
    unit_line, system = scene_units(scene_file) if scene_file else (None, {})
    notes = scene_comments(scene_file) if scene_file else {}

    h = ['<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">',
         '<meta name="viewport" content="width=device-width, initial-scale=1">',
         "<title>%s: run report</title><style>%s</style></head><body>" % (html.escape(scene),
                                                                          CSS)]
    h.append("<h1>%s</h1>" % html.escape(scene))
    if scene_file:
        h.append('<p class="muted">scene file <code>%s</code></p>' % html.escape(scene_file))
    status = run.get("status", "complete" if summary else "stopped")
    words = {"complete": "Run complete.", "stopped": "Run stopped before its end.",
             "failed": "Run failed.", "running": "Run in progress."}.get(status, status)
    message = run.get("message", "")
    h.append('<div class="status %s"><b>%s</b> %s</div>' % (
        html.escape(status), html.escape(words), html.escape(message)))
    if summary is not None and run and run.get("summary_from_this_run") is False:
        h.append('<p class="muted">The parameters, results and charts below are those of an '
                 "earlier run in this folder (its summary.json).</p>")

    # Run: wall time and machine.
    if run:
        order = [("wall_time_s", "wall time", "s"), ("started_utc", "started (UTC)", ""),
                 ("finished_utc", "finished (UTC)", ""), ("hostname", "host", ""),
                 ("cpu", "processor", ""), ("cores", "cores", ""),
                 ("threads", "host threads", ""), ("ranks", "MPI ranks", ""),
                 ("execution_space", "execution space", ""),
                 ("kokkos_backends", "Kokkos backends", ""),
                 ("kokkos_version", "Kokkos", ""), ("granular_version", "granular", ""),
                 ("system", "system", "")]
        rows = [["<td>%s</td>" % label, cell(run[k]), "<td>%s</td>" % unit]
                for k, label, unit in order if k in run]
        h.append("<h2>Run</h2>" + table(["", "value", "unit"], rows))

    if summary is not None:
        params = summary.get("parameters") or {}
        if params:
            h.append("<h2>Parameters</h2>")
            if unit_line:
                h.append('<p class="muted">Units of the scene: %s</p>' % html.escape(unit_line))
            noted = any(k in notes for k in params)
            rows = [["<td><code>%s</code></td>" % html.escape(k), cell(v, whole=True)] +
                    (["<td>%s</td>" % html.escape(notes.get(k, ""))] if noted else [])
                    for k, v in params.items()]
            h.append(table(["key", "value"] + (["note in the scene file"] if noted else []),
                           rows))
        res = results_html(summary, system)
        if res:
            h.append("<h2>Results</h2>")
            if system:
                h.append('<p class="muted">Units are read from the key names in the scene\'s '
                         "unit system; a blank unit is one the name does not tell (see the "
                         "scene file and its page under docs/).</p>")
            h.append(res)

    charts = sorted(f for f in os.listdir(out)
                    if f.lower().endswith(".png") and not f.startswith("."))
    if charts:
        h.append("<h2>Charts</h2>")
        for name in charts:
            with open(os.path.join(out, name), "rb") as f:
                data = base64.b64encode(f.read()).decode("ascii")
            h.append('<figure><img alt="%s" src="data:image/png;base64,%s">'
                     "<figcaption>%s</figcaption></figure>" % (html.escape(name), data,
                                                               html.escape(name)))

    files = sorted(f for f in os.listdir(out)
                   if not f.startswith(".") and f != "report.html"
                   and os.path.isfile(os.path.join(out, f)) and not f.lower().endswith(".png"))
    if files:
        h.append("<h2>Data files</h2><ul class=\"files\">")
        for name in files:
            what = ""
            if name.endswith(".xdmf"):
                what = " — open in ParaView (File → Open, Xdmf3 reader)"
            elif name == "results.h5":
                what = " — every series and table of the run (HDF5)"
            h.append('<li><a href="%s">%s</a> <span class="muted">%s%s</span></li>' % (
                html.escape(name, quote=True), html.escape(name),
                size_text(os.path.getsize(os.path.join(out, name))), html.escape(what)))
        h.append("</ul>")
    h.append("</body></html>\n")

    path = os.path.join(out, "report.html")
    tmp = os.path.join(out, ".report.html.partial")
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write("".join(h))
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as e:
        # A full disk or a read-only folder: one line that says what, no traceback, and no
        # partial file left behind (an earlier report was removed when the run began).
        try:
            os.remove(tmp)
        except OSError:
            pass
        sys.exit(f"report.py: {path} not written: {e.strerror or e}")


if __name__ == "__main__":
    main(sys.argv)
