#!/usr/bin/env python3
"""Combines the sweeps of reports/thesis/make.sh into tables.json and index.html: the thesis's
Tables 6.1/6.2 at 512x512 (cache/cpu_*/), the parameter study (cache/study/*/ and the
conventions and rest_model runs of cache/cpu_*/), Figures 6.2/6.3 and the error attribution of
the GPU sweeps (1uun/, cool_random/), and the written comparison (comparison.html). Standard
library only; reads each sweep's sweep.json and summary.json and cache/info_*.json,
cache/wall_*.txt; copies the 512x512 images the page shows into 512/."""

import argparse
import html
import json
import math
import os
import shutil

HERE = os.path.dirname(os.path.abspath(__file__))
SETS = ("1uun", "cool_random")

# The thesis's published SSIM against its own GT (N = all), Tables 6.1 and 6.2, as fractions.
PUBLISHED = {
    "1uun": {
        1: (0.898914, 0.960094, 0.951042, 0.936683),
        2: (0.988771, 0.996152, 0.99505, 0.993324),
        3: (0.999335, 0.999758, 0.999708, 0.999601),
        5: (0.999996, 0.999998, 0.999998, 0.999997),
    },
    "cool_random": {
        1: (0.770101, 0.841127, 0.703878, 0.771702),
        2: (0.923301, 0.951143, 0.880297, 0.918247),
        5: (0.999073, 0.999413, 0.999012, 0.999166),
        10: (0.999995, 0.999997, 0.999997, 0.999996),
    },
}
TITLES = {
    "1uun": ("Table 6.1 / Figure 6.2: 1UUN", "chains A and B of 1UUN, OPM orientation",
             "../shared/data/pdb/1uun_opm_oriented.pdb (chains A, B)"),
    "cool_random": ("Table 6.2 / Figure 6.3: \"cool random\"", "the thesis's own random set",
                    "../shared/data/mmpld/cool_random.mmpld"),
}
CHANNELS = ("R", "G", "B")
SAMPLES = 100

# What the thesis leaves open, as the study varies it: (key, what, default, alternatives); each
# alternative names the sweep and the rest_model and convention it is read with.
ASSUMPTIONS = [
    ("theta", "Θmax (opacity along a particle's diameter)", "0.5", ["0.3", "0.7", "0.9"]),
    ("radius", "radius scale", "1", ["0.8", "1.25"]),
    ("lights", "light weights", "mean (w = 1/2)", ["sum (w = 1)"]),
    ("rest", "the simplified model past N",
     "emission C(1−T), as the shader", ["absorption only", "lit without shadow rays"]),
    ("normalize", "normalisation before SSIM", "none", ["max", "channel-max"]),
    ("quantize", "bit depth before SSIM", "float", ["8 bit"]),
]
SCENE_VARIANT = {("theta", "0.3"): "theta_0.3", ("theta", "0.7"): "theta_0.7",
                 ("theta", "0.9"): "theta_0.9", ("radius", "0.8"): "radius_0.8",
                 ("radius", "1.25"): "radius_1.25", ("lights", "sum (w = 1)"): "lights_sum"}
REST = {"emission C(1−T), as the shader": 0, "absorption only": 1, "lit without shadow rays": 2}
# 1 − SSIM below this counts as this (two identical 8-bit images have 1 − SSIM = 0).
FLOOR = 1e-9


def load(*parts):
    with open(os.path.join(HERE, *parts), encoding="utf-8") as f:
        return json.load(f)


def wall(name):
    path = os.path.join(HERE, "cache", "wall_%s.txt" % name)
    if not os.path.exists(path):
        return None
    with open(path, encoding="utf-8") as f:
        return float(f.read().strip())


def channels(d):
    return {k: d[k] for k in ("R", "G", "B", "mean")} if d else None


def gt_values(sweep, convention=None):
    """{(rest_model, n): {R, G, B, mean}} of the thesis-cpu runs against the GT, as stored
    (convention None) or under a convention."""
    out = {}
    for r in sweep:
        if r["method"] != "thesis-cpu" or "baseline" not in r:
            continue
        b = r["baseline"]
        v = b["ssim"] if convention is None else b.get("conventions", {}).get(convention, {}).get("ssim")
        if v:
            out[(r["params"].get("rest_model", 0), r["params"]["n_exact"])] = channels(v)
    return out


def cpu_table(name):
    """The 512x512 table: thesis-cpu N against the exact reference and the thesis's GT."""
    d = os.path.join(HERE, "cache", "cpu_" + name)
    sweep = load(d, "sweep.json")
    summary = load(d, "summary.json")
    rows = []
    for r in sweep:
        p = r["params"]
        if r["method"] != "thesis-cpu" or p.get("rest_model", 0) != 0:
            continue
        n = p["n_exact"]
        pub = PUBLISHED[name].get(n)
        rows.append({
            "n_exact": n,
            "vs_exact": channels(r["ssim"]),
            "vs_thesis_gt": channels(r.get("baseline", {}).get("ssim")),
            "published": dict(zip(("R", "G", "B", "mean"), pub)) if pub else None,
            "rmse_vs_exact": r["rmse"]["mean"],
            "cpu_seconds": r["seconds"],
            "image": r["image"],
        })
    return sweep, summary, rows


def copy_images(name, rows):
    """The reference and the N = 1 and N = all images at 512x512, into 512/ (committed)."""
    out = os.path.join(HERE, "512")
    os.makedirs(out, exist_ok=True)
    src = os.path.join(HERE, "cache", "cpu_" + name)
    pictures = [("reference.png", "%s_reference.png" % name, "exact reference")]
    for r in rows:
        if r["n_exact"] in (1, "all"):
            pictures.append((r["image"], "%s_n_exact_%s.png" % (name, r["n_exact"]),
                             "thesis-cpu N = %s" % r["n_exact"]))
    shown = []
    for s, dst, caption in pictures:
        shutil.copyfile(os.path.join(src, s), os.path.join(out, dst))
        shown.append(("512/" + dst, caption))
    return shown


def gpu_dataset(name):
    runs = load(name, "sweep.json")
    summary = load(name, "summary.json")
    rows = []
    for r in runs:
        p = r["params"]
        if r["method"] != "thesis" or p.get("samples") != SAMPLES:
            continue
        rows.append({
            "n_exact": p["n_exact"],
            "vs_exact": channels(r["ssim"]),
            "vs_thesis_gt": channels(r.get("baseline", {}).get("ssim")),
            "gpu_seconds": r["seconds"],
            "image": "%s/%s" % (name, r["image"]),
        })
    timing = [
        {"method": r["method"], "samples": r["params"].get("samples"),
         "n_exact": r["params"].get("n_exact"), "seconds": r["seconds"],
         "ssim_vs_exact": r["ssim"]["mean"]}
        for r in runs
    ]
    attributions = summary["attribution"]
    float32 = {}
    for a in attributions:
        for c in a["causes"]:
            if c["cause"] == "float32":
                float32[a["run"]] = {"mse_share": c["mse_share"], "ssim_share": c["ssim_share"],
                                     "rmse": c["rmse"]}
    return {
        "size": summary["size"],
        "rows": rows,
        "attributions": attributions,
        "float32": float32,
        "reference_seconds": summary["reference_seconds"],
        "threads": summary["threads"],
        "adapter": summary["adapter"],
        "sweep_wall_seconds": wall(name),
        "timing": timing,
    }


def dissimilarity(v):
    return max(1.0 - v, FLOOR)


def log_residual(value, published):
    """log10 of pgt's 1 − SSIM over the published one: 0 reproduces, +1 ten times the loss."""
    return math.log10(dissimilarity(value) / dissimilarity(published))


def study(name):
    """Every configuration of the study with its cells, the default, the best fit, and per cell
    the assumption that moves it most."""
    if name == "1uun":
        base = load("cache", "cpu_1uun", "sweep.json")
        base_size = load("cache", "cpu_1uun", "summary.json")["size"]
    else:
        base = load("cache", "study", "cool_random_default", "sweep.json")
        base_size = load("cache", "study", "cool_random_default", "summary.json")["size"]
    variants = {None: base}
    for (key, value), stem in SCENE_VARIANT.items():
        variants[stem] = load("cache", "study", "%s_%s" % (name, stem), "sweep.json")
    conventions = [(None, "none", "float"), ("8bit", "none", "8 bit"), ("max", "max", "float"),
                   ("max-8bit", "max", "8 bit"), ("channel-max", "channel-max", "float"),
                   ("channel-max-8bit", "channel-max", "8 bit")]
    published = PUBLISHED[name]
    configs = []
    for stem, sweep in variants.items():
        scene = {"theta": "0.5", "radius": "1", "lights": "mean (w = 1/2)"}
        for (key, value), s in SCENE_VARIANT.items():
            if s == stem:
                scene[key] = value
        for rest_name, rest in REST.items():
            for conv, normalize, quantize in conventions:
                values = gt_values(sweep, conv)
                cells = {}
                for n in published:
                    v = values.get((rest, n))
                    if v is None:
                        break
                    cells[n] = v
                if len(cells) != len(published):
                    continue
                assumptions = dict(scene, rest=rest_name, normalize=normalize, quantize=quantize)
                cost = sum(log_residual(cells[n][c], published[n][i]) ** 2
                           for n in published for i, c in enumerate(CHANNELS))
                configs.append({"assumptions": assumptions, "cells": cells, "cost": cost})
    default = next(c for c in configs if all(
        c["assumptions"][k] == d for k, _, d, _ in ASSUMPTIONS))
    best = min(configs, key=lambda c: c["cost"])
    cells = []
    for n, pub in published.items():
        for i, c in enumerate(CHANNELS + ("mean",)):
            moves = []
            for key, _, d, alternatives in ASSUMPTIONS:
                for alt in alternatives:
                    want = dict(default["assumptions"], **{key: alt})
                    other = next((x for x in configs if x["assumptions"] == want), None)
                    if other is not None:
                        change = abs(log_residual(other["cells"][n][c], default["cells"][n][c]))
                        moves.append((change, key, alt, other["cells"][n][c]))
            top = max(moves)
            closest = min(configs, key=lambda x: abs(log_residual(x["cells"][n][c], pub[i])))
            cells.append({
                "n_exact": n, "channel": c, "published": pub[i],
                "default": default["cells"][n][c], "fitted": best["cells"][n][c],
                "residual_points": 100.0 * (best["cells"][n][c] - pub[i]),
                "residual_log10": log_residual(best["cells"][n][c], pub[i]),
                "moved_most_by": {"assumption": top[1], "value": top[2], "ssim": top[3],
                                  "log10_change": top[0]},
                "closest_any": {"assumptions": closest["assumptions"], "ssim": closest["cells"][n][c],
                                "residual_log10": log_residual(closest["cells"][n][c], pub[i])},
            })
    return {
        "size": base_size,
        "configurations": len(configs),
        "default": {"assumptions": default["assumptions"], "cost": default["cost"]},
        "fitted": {"assumptions": best["assumptions"], "cost": best["cost"]},
        "cells": cells,
        "ranked": [{"assumptions": c["assumptions"], "cost": c["cost"]}
                   for c in sorted(configs, key=lambda c: c["cost"])[:5]],
    }


def pct(v, digits=4):
    return "—" if v is None else "%.*f%%" % (digits, 100.0 * v)


def cells_html(d):
    if not d:
        return "<td>—</td>" * 4
    return "".join("<td>%s</td>" % pct(d[k], 3) for k in CHANNELS) + "<td><b>%s</b></td>" % pct(d["mean"], 4)


def cpu_table_html(rows):
    head = ("<table><tr><th rowspan=2>N</th><th colspan=4>pgt (thesis-cpu): against the exact reference</th>"
            "<th colspan=4>pgt (thesis-cpu): against the thesis's GT (N = all)</th>"
            "<th colspan=4>thesis, published (against its GT)</th><th rowspan=2>CPU s</th></tr>\n<tr>"
            + "<th>R</th><th>G</th><th>B</th><th>mean</th>" * 3 + "</tr>\n")
    body = "".join(
        "<tr><td>%s</td>%s%s%s<td>%.1f</td></tr>\n"
        % (r["n_exact"], cells_html(r["vs_exact"]), cells_html(r["vs_thesis_gt"]),
           cells_html(r["published"]), r["cpu_seconds"])
        for r in rows)
    return head + body + "</table>\n"


def gpu_table_html(rows):
    head = ("<table><tr><th rowspan=2>N</th><th colspan=4>pgt (thesis, GPU): against the exact reference</th>"
            "<th colspan=4>pgt (thesis, GPU): against the thesis's GT (N = all)</th><th rowspan=2>GPU s</th></tr>\n<tr>"
            + "<th>R</th><th>G</th><th>B</th><th>mean</th>" * 2 + "</tr>\n")
    body = "".join(
        "<tr><td>%s</td>%s%s<td>%.3f</td></tr>\n"
        % (r["n_exact"], cells_html(r["vs_exact"]), cells_html(r["vs_thesis_gt"]), r["gpu_seconds"])
        for r in rows)
    return head + body + "</table>\n"


def figure(src, caption, bar=None):
    img = '<img src="%s" alt="%s">' % (html.escape(src), html.escape(caption))
    if bar:
        img = '<div class="heat">%s<img src="%s" class="bar" alt="colour bar of %s"></div>' % (
            img, html.escape(bar), html.escape(caption))
    return "<figure>%s<figcaption>%s</figcaption></figure>\n" % (img, html.escape(caption))


def attribution_html(name, d):
    out = ""
    for a in d["attributions"]:
        out += "<h4>%s</h4>\n" % html.escape(a["run"])
        out += '<div class="plot">%s</div>\n' % figure("%s/%s" % (name, a["bars"]), "shares of the error of " + a["run"])
        out += ("<table><tr><th>cause</th><th>swap</th><th>RMSE of its map</th><th>SSIM before vs after</th>"
                "<th>SSIM share</th><th>MSE share</th></tr>\n")
        for c in a["causes"]:
            out += ("<tr><td>%s</td><td>%s → %s</td><td>%.3e</td><td>%s</td><td>%.1f%%</td><td>%.1f%%</td></tr>\n"
                    % (html.escape(c["cause"]), html.escape(c["from"]), html.escape(c["to"]), c["rmse"],
                       pct(c["ssim"]), 100 * c["ssim_share"], 100 * c["mse_share"]))
        out += "<tr><td>interaction</td><td>cross terms</td><td></td><td></td><td></td><td>%.1f%%</td></tr></table>\n" % (100 * a["interaction"])
        bar = "%s/%s" % (name, a["scale"])
        out += '<div class="grid">' + "".join(
            figure("%s/%s" % (name, c["map"]), "%s: |before − after| (magma, one scale per run)" % c["cause"], bar)
            for c in a["causes"]) + "</div>\n"
    return out


def section(name, d):
    title, what, _ = TITLES[name]
    g = d["gpu"]
    out = "<h2 id=\"%s\">%s</h2>\n" % (name, html.escape(title))
    out += ("<p>%s particles (%s). <b>Table at the thesis's 512×512</b>, %d samples per particle, the "
            "thesis's scheme in f64 on the CPU (<code>thesis-cpu</code>, %d threads; the sweep took %.0f s "
            "with its exact reference and the study's rest_model runs):</p>\n"
            % ("{:,}".format(d["particles"]), what, SAMPLES, d["cpu_threads"], d["cpu_wall_seconds"] or 0))
    out += cpu_table_html(d["rows"])
    out += ("<p><b>The GPU method</b> (<code>thesis</code>, float32) at %d×%d on <b>%s</b> (the sweep took "
            "%.0f s): its SSIM, its times for the figure below, and the error attribution, whose "
            "<i>float32</i> cause is what separates it from <code>thesis-cpu</code> above.</p>\n"
            % (g["size"][0], g["size"][1], html.escape(str(g["adapter"])), g["sweep_wall_seconds"] or 0))
    out += gpu_table_html(g["rows"])
    out += "<h3>Render time against samples, one line per N (the thesis's figure), and error against time</h3>\n"
    out += '<div class="grid">' + figure(name + "/time.svg", "time against samples (%s)" % name)
    out += figure(name + "/error_time.svg", "1 − SSIM against time (%s)" % name)
    out += figure(name + "/dssim.svg", "1 − SSIM against samples (%s)" % name)
    out += figure(name + "/dssim_baseline.svg", "1 − SSIM against the thesis's GT (%s)" % name) + "</div>\n"
    out += "<h3>Error attribution (GPU, %d×%d)</h3>\n" % tuple(g["size"]) + attribution_html(name, g)
    out += "<h3>Images at 512×512</h3>\n<div class=\"grid\">"
    for src, caption in d["images"]:
        out += figure(src, caption)
    return out + "</div>\n"


def svg_plot(name, s):
    """1 − SSIM (mean over R, G, B) against N: published, pgt default, pgt fitted; log scale."""
    pub = PUBLISHED[name]
    ns = list(pub)
    series = [
        ("published", "#222", [1 - pub[n][3] for n in ns]),
        ("pgt, default assumptions", "#1f77b4",
         [1 - next(c["default"] for c in s["cells"] if c["n_exact"] == n and c["channel"] == "mean") for n in ns]),
        ("pgt, fitted assumptions", "#d62728",
         [1 - next(c["fitted"] for c in s["cells"] if c["n_exact"] == n and c["channel"] == "mean") for n in ns]),
    ]
    w, h, left, right, top, bottom = 620, 360, 70, 190, 20, 45
    values = [max(v, FLOOR) for _, _, vs in series for v in vs]
    lo = math.floor(math.log10(min(values)))
    hi = math.ceil(math.log10(max(values)))
    if hi == lo:
        hi += 1

    def x(i):
        return left + (w - left - right) * (i / max(len(ns) - 1, 1))

    def y(v):
        return top + (h - top - bottom) * (hi - math.log10(max(v, FLOOR))) / (hi - lo)

    out = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" viewBox="0 0 %d %d" '
           'font-family="sans-serif" font-size="12">' % (w, h, w, h),
           '<rect width="%d" height="%d" fill="white"/>' % (w, h)]
    for e in range(lo, hi + 1):
        yy = y(10.0 ** e)
        out.append('<line x1="%d" x2="%d" y1="%.1f" y2="%.1f" stroke="#ddd"/>' % (left, w - right, yy, yy))
        out.append('<text x="%d" y="%.1f" text-anchor="end">1e%d</text>' % (left - 6, yy + 4, e))
    for i, n in enumerate(ns):
        out.append('<text x="%.1f" y="%d" text-anchor="middle">%s</text>' % (x(i), h - bottom + 18, n))
    out.append('<text x="%d" y="%d" text-anchor="middle">N (particles with the lit model)</text>'
               % ((left + w - right) // 2, h - 8))
    out.append('<text x="14" y="%d" transform="rotate(-90 14 %d)" text-anchor="middle">1 − SSIM against the GT (mean of R, G, B)</text>'
               % ((top + h - bottom) // 2, (top + h - bottom) // 2))
    for k, (label, colour, vs) in enumerate(series):
        points = " ".join("%.1f,%.1f" % (x(i), y(v)) for i, v in enumerate(vs))
        out.append('<polyline points="%s" fill="none" stroke="%s" stroke-width="2"/>' % (points, colour))
        for i, v in enumerate(vs):
            out.append('<circle cx="%.1f" cy="%.1f" r="3" fill="%s"/>' % (x(i), y(v), colour))
        ly = top + 14 + 18 * k
        out.append('<line x1="%d" x2="%d" y1="%d" y2="%d" stroke="%s" stroke-width="2"/>' % (w - right + 10, w - right + 30, ly, ly, colour))
        out.append('<text x="%d" y="%d">%s</text>' % (w - right + 35, ly + 4, html.escape(label)))
    out.append("</svg>\n")
    path = os.path.join(HERE, "study_%s.svg" % name)
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(out))
    return "study_%s.svg" % name


SHORT = {"theta": "Θmax", "radius": "radius ×", "lights": "lights", "rest": "past N:",
         "normalize": "normalisation", "quantize": "bit depth"}


def assumptions_text(a):
    return ", ".join("%s %s" % (SHORT[key], a[key]) for key, _, _, _ in ASSUMPTIONS)


def study_html(data):
    out = "<h3>The assumptions</h3>\n<table><tr><th>assumption</th><th>pgt's default</th><th>tried</th>"
    out += "".join("<th>fitted, %s</th>" % html.escape(TITLES[n][0].split(": ")[1]) for n in SETS) + "</tr>\n"
    for key, label, default, alternatives in ASSUMPTIONS:
        out += "<tr><td>%s</td><td>%s</td><td>%s</td>%s</tr>\n" % (
            html.escape(label), html.escape(default), html.escape(", ".join(alternatives)),
            "".join("<td>%s</td>" % html.escape(data[n]["study"]["fitted"]["assumptions"][key]) for n in SETS))
    out += "</table>\n"
    for name in SETS:
        s = data[name]["study"]
        out += "<h3>%s: every cell</h3>\n" % html.escape(TITLES[name][0].split(": ")[1])
        out += ("<p>At %d×%d; %d configurations compared. Fit: the configuration with the least sum over the R, G, B "
                "cells of (log₁₀ of pgt's 1 − SSIM over the published 1 − SSIM)². Default: sum %.2f; fitted: sum %.2f.</p>\n"
                % (s["size"][0], s["size"][1], s["configurations"], s["default"]["cost"], s["fitted"]["cost"]))
        out += ("<table><tr><th>N</th><th>channel</th><th>published</th><th>pgt, default</th><th>pgt, fitted</th>"
                "<th>residual (points)</th><th>log₁₀ of the 1 − SSIM ratio</th><th>moved most by</th></tr>\n")
        for c in s["cells"]:
            m = c["moved_most_by"]
            out += ("<tr><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%+.3f</td><td>%+.2f</td>"
                    "<td>%s → %s (%s)</td></tr>\n"
                    % (c["n_exact"], c["channel"], pct(c["published"]), pct(c["default"]), pct(c["fitted"]),
                       c["residual_points"], c["residual_log10"], html.escape(m["assumption"]),
                       html.escape(m["value"]), pct(m["ssim"])))
        out += "</table>\n"
        out += '<div class="grid">' + figure(svg_plot(name, s), "1 − SSIM against N: published, pgt default, pgt fitted (%s)" % name) + "</div>\n"
    return out


CSS = """body{font-family:sans-serif;max-width:1300px;margin:1em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:.5em 0;font-size:13px}td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}
th{background:#eee}.grid{display:flex;flex-wrap:wrap;gap:8px}figure{margin:0}
figure img{image-rendering:pixelated;max-width:640px}figcaption{font-size:12px;max-width:320px}
.grid figure img[src$=".png"]{width:256px}.grid figure img[src$=".svg"]{width:620px}
.heat{display:flex;align-items:flex-start;gap:.3em}.grid figure img.bar{width:auto}"""


# The mark the browser test reads (the same script as pgt's own pages, src/report/html.rs).
SCRIPT = """<script>
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images);
  var broken = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); });
  document.body.setAttribute("data-pgt-images", broken.length === 0 ? "ok" : "missing");
  document.body.setAttribute("data-pgt-image-count", String(imgs.length));
  if (broken.length > 0) {
    document.body.setAttribute("data-pgt-broken", broken.map(function (i) { return i.getAttribute("src"); }).join(" "));
  }
});
</script>"""


def page(data, text):
    body = "<h1>The thesis's evaluation (chapter 6), reproduced with pgt</h1>\n"
    body += text.replace("{study}", study_html(data))
    for name in SETS:
        body += section(name, data[name])
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>pgt: the thesis's evaluation</title>"
            "<style>%s</style></head><body data-pgt-images=\"pending\">\n%s%s\n</body></html>\n" % (CSS, body, SCRIPT))


def row(d, n):
    return next((r for r in d["rows"] if r["n_exact"] == n), None)


def mean(d, n, key):
    r = row(d, n)
    return r[key]["mean"] if r and r[key] else None


def shares(g, run):
    """'overlap 17.2 %, sampling 0.0 %, …' of the MSE of one attributed run, largest first."""
    for a in g["attributions"]:
        if a["run"] == run:
            parts = sorted(((c["mse_share"], c["cause"]) for c in a["causes"]), reverse=True)
            text = ", ".join("%s %.3g%%" % (name, 100 * v) for v, name in parts)
            return text + ", interaction %.2g%%" % (100 * a["interaction"])
    return "not measured"


# A cell counts as reproduced when pgt's 1 − SSIM is within this factor of the published one.
WITHIN = 2.0


def float32_share(g, run):
    f = g["float32"].get(run)
    return "not measured" if f is None else "%.2g %% of the MSE" % (100 * f["mse_share"])


def cell_name(c):
    return "N = %s %s" % (c["n_exact"], c["channel"])


def reproduced(s, yes):
    """The R, G, B cells the fitted assumptions reproduce (yes) or do not, as text."""
    limit = math.log10(WITHIN)
    cells = [c for c in s["cells"] if c["channel"] != "mean"
             and (abs(c["residual_log10"]) <= limit) == yes]
    return ", ".join(cell_name(c) for c in cells) or "none"


def never(s):
    """The R, G, B cells no configuration of the study reproduces, with the closest value."""
    limit = math.log10(WITHIN)
    cells = [c for c in s["cells"] if c["channel"] != "mean"
             and abs(c["closest_any"]["residual_log10"]) > limit]
    return ", ".join("%s (published %s, closest %s)" % (cell_name(c), pct(c["published"]),
                                                       pct(c["closest_any"]["ssim"]))
                     for c in cells) or "none"


def written(data, gpu_side, total):
    u, r = data["1uun"], data["cool_random"]
    text = open(os.path.join(HERE, "comparison.html"), encoding="utf-8").read()
    values = dict(
        gpu_side=gpu_side, total="%.0f" % total if total is not None else "(not measured)",
        u1=pct(mean(u, 1, "vs_thesis_gt"), 2), u5=pct(mean(u, 5, "vs_thesis_gt"), 4),
        u1x=pct(mean(u, 1, "vs_exact"), 2), u5x=pct(mean(u, 5, "vs_exact"), 3), uallx=pct(mean(u, "all", "vs_exact"), 3),
        r1=pct(mean(r, 1, "vs_thesis_gt"), 2), r10=pct(mean(r, 10, "vs_thesis_gt"), 4),
        r1x=pct(mean(r, 1, "vs_exact"), 2), r10x=pct(mean(r, 10, "vs_exact"), 3), rallx=pct(mean(r, "all", "vs_exact"), 3),
        adapter=html.escape(str(u["gpu"]["adapter"])), threads=u["cpu_threads"],
        au5=shares(u["gpu"], "thesis samples=100 n_exact=5"), auall=shares(u["gpu"], "thesis samples=100 n_exact=all"),
        ar5=shares(r["gpu"], "thesis samples=100 n_exact=5"), arall=shares(r["gpu"], "thesis samples=100 n_exact=all"),
        uf=assumptions_text(u["study"]["fitted"]["assumptions"]),
        rf=assumptions_text(r["study"]["fitted"]["assumptions"]),
        au5f=float32_share(u["gpu"], "thesis samples=100 n_exact=5"),
        ar5f=float32_share(r["gpu"], "thesis samples=100 n_exact=5"),
        arallf=float32_share(r["gpu"], "thesis samples=100 n_exact=all"),
        ureproduced=reproduced(u["study"], True), unot=reproduced(u["study"], False),
        rreproduced=reproduced(r["study"], True), rnot=reproduced(r["study"], False),
        unever=never(u["study"]), rnever=never(r["study"]),
    )
    findings = open(os.path.join(HERE, "findings.html"), encoding="utf-8").read()
    for k, v in values.items():
        findings = findings.replace("{%s}" % k, str(v))
    values["findings"] = findings
    for k, v in values.items():
        text = text.replace("{%s}" % k, str(v))
    return text


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--gpu-side", type=int, required=True)
    args = ap.parse_args()
    data = {}
    for name in SETS:
        sweep, summary, rows = cpu_table(name)
        data[name] = {
            "data_file": TITLES[name][2],
            "particles": load("cache", "info_%s.json" % name)["particles"],
            "size": summary["size"],
            "samples": SAMPLES,
            "rows": rows,
            "cpu_threads": summary["threads"],
            "cpu_wall_seconds": wall("cpu_" + name),
            "reference_seconds": summary["reference_seconds"],
            "images": copy_images(name, rows),
            "gpu": gpu_dataset(name),
            "study": study(name),
        }
    total = wall("total")
    tables = {}
    for name, d in data.items():
        t = {k: v for k, v in d.items() if k not in ("gpu", "images")}
        t["gpu"] = {k: v for k, v in d["gpu"].items() if k not in ("attributions", "timing")}
        tables[name] = t
    tables["wall_seconds"] = total
    tables["note"] = ("SSIM as fractions. Each data set: rows are thesis-cpu (the thesis's scheme in f64) at size "
                      "(512x512), against the exact reference and against the thesis's GT (N = all); gpu holds the "
                      "GPU method thesis at its own size on the named adapter (gpu_seconds: timestamp-query GPU "
                      "times) and float32's share of its error; study holds the parameter study: the default and "
                      "fitted assumptions, and per published cell the default, fitted and published values, the "
                      "residual and the assumption that moves the cell most. Published values are the thesis's "
                      "Tables 6.1/6.2 (against its own GT). wall_seconds: make.sh from start to end.")
    with open(os.path.join(HERE, "tables.json"), "w", encoding="utf-8") as f:
        json.dump(tables, f, indent=2)
        f.write("\n")
    with open(os.path.join(HERE, "index.html"), "w", encoding="utf-8") as f:
        f.write(page(data, written(data, args.gpu_side, total)))


if __name__ == "__main__":
    main()
