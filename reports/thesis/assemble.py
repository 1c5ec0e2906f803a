#!/usr/bin/env python3
"""Combines the two sweeps of reports/thesis/make.sh (1uun/, random/) into tables.json and
index.html: the thesis's Tables 6.1/6.2 beside pgt's measurements, Figures 6.2/6.3 redrawn,
the error attribution, and the written comparison. Standard library only; reads
DIR/sweep.json, DIR/summary.json and cache/info_*.json, cache/wall_*.txt."""

import argparse
import html
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))

# The thesis's published SSIM against its own GT (N = all), Tables 6.1 and 6.2, as fractions.
PUBLISHED = {
    "1uun": {
        1: (0.898914, 0.960094, 0.951042, 0.936683),
        2: (0.988771, 0.996152, 0.99505, 0.993324),
        3: (0.999335, 0.999758, 0.999708, 0.999601),
        5: (0.999996, 0.999998, 0.999998, 0.999997),
    },
    "random": {
        1: (0.770101, 0.841127, 0.703878, 0.771702),
        2: (0.923301, 0.951143, 0.880297, 0.918247),
        5: (0.999073, 0.999413, 0.999012, 0.999166),
        10: (0.999995, 0.999997, 0.999997, 0.999996),
    },
}
TITLES = {
    "1uun": ("Table 6.1 / Figure 6.2: 1UUN", "chains A and B of 1UUN (OPM orientation)"),
    "random": ("Table 6.2 / Figure 6.3: the random set", "pgt gen random's defaults (seed 1)"),
}
SAMPLES = 100


def load(*parts):
    with open(os.path.join(HERE, *parts), encoding="utf-8") as f:
        return json.load(f)


def channels(d):
    return {k: d[k] for k in ("R", "G", "B", "mean")} if d else None


def dataset(name, side):
    runs = load(name, "sweep.json")
    summary = load(name, "summary.json")
    info = load("cache", "info_%s.json" % name)
    with open(os.path.join(HERE, "cache", "wall_%s.txt" % name), encoding="utf-8") as f:
        wall = float(f.read().strip())
    rows = []
    for r in runs:
        p = r["params"]
        if r["method"] != "thesis" or p.get("samples") != SAMPLES:
            continue
        n = p["n_exact"]
        pub = PUBLISHED[name].get(n)
        rows.append({
            "n_exact": n,
            "vs_exact": channels(r["ssim"]),
            "vs_thesis_gt": channels(r.get("baseline", {}).get("ssim")),
            "published": dict(zip(("R", "G", "B", "mean"), pub)) if pub else None,
            "rmse_vs_exact": r["rmse"]["mean"],
            "gpu_seconds": r["seconds"],
            "adapter": summary["adapter"],
            "image": "%s/%s" % (name, r["image"]),
        })
    timing = [
        {"method": r["method"], "samples": r["params"].get("samples"),
         "n_exact": r["params"].get("n_exact"), "seconds": r["seconds"],
         "ssim_vs_exact": r["ssim"]["mean"]}
        for r in runs
    ]
    attribution = {}
    attributions = summary["attribution"]
    for a in attributions:
        if a["run"] == "thesis samples=%d n_exact=5" % SAMPLES:
            attribution = {
                c["cause"]: {"rmse": c["rmse"], "ssim": c["ssim"], "ssim_share": c["ssim_share"],
                             "mse_share": c["mse_share"], "swap": "%s -> %s" % (c["from"], c["to"]),
                             "map": "%s/%s" % (name, c["map"])}
                for c in a["causes"]
            }
            attribution["interaction"] = {"mse_share": a["interaction"]}
            attribution["run"] = a["run"]
    return {
        "particles": info["particles"],
        "size": summary["size"],
        "samples": SAMPLES,
        "rows": rows,
        "attribution": attribution,
        "attributions": attributions,
        "reference_seconds": summary["reference_seconds"],
        "threads": summary["threads"],
        "adapter": summary["adapter"],
        "sweep_wall_seconds": wall,
        "timing": timing,
    }


def pct(v, digits=4):
    return "—" if v is None else "%.*f%%" % (digits, 100.0 * v)


def cells(d):
    if not d:
        return "<td>—</td>" * 4
    return "".join("<td>%s</td>" % pct(d[k], 3) for k in ("R", "G", "B")) + "<td><b>%s</b></td>" % pct(d["mean"], 4)


def table(name, d):
    head = ("<table><tr><th rowspan=2>N</th><th colspan=4>pgt: against the exact reference</th>"
            "<th colspan=4>pgt: against the thesis's GT (N = all)</th>"
            "<th colspan=4>thesis, published (against its GT)</th><th rowspan=2>GPU s</th></tr>\n<tr>"
            + "<th>R</th><th>G</th><th>B</th><th>mean</th>" * 3 + "</tr>\n")
    body = "".join(
        "<tr><td>%s</td>%s%s%s<td>%.3f</td></tr>\n"
        % (r["n_exact"], cells(r["vs_exact"]), cells(r["vs_thesis_gt"]), cells(r["published"]),
           r["gpu_seconds"])
        for r in d["rows"])
    return head + body + "</table>\n"


def figure(src, caption):
    return ('<figure><img src="%s" alt="%s"><figcaption>%s</figcaption></figure>\n'
            % (html.escape(src), html.escape(caption), html.escape(caption)))


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
        out += '<div class="grid">' + "".join(
            figure("%s/%s" % (name, c["map"]), "%s: |before − after|" % c["cause"]) for c in a["causes"]) + "</div>\n"
    return out


def section(name, d, side):
    title, what = TITLES[name]
    out = "<h2 id=\"%s\">%s</h2>\n" % (name, html.escape(title))
    out += ("<p>%s particles (%s), %d×%d pixels, %d samples per particle. Exact reference: %s on %d CPU threads. "
            "GPU times: %s. The whole sweep (%d runs, CPU stages included) took %.0f s. "
            "<a href=\"%s/index.html\">The full sweep page</a> has every run, its image and its error map.</p>\n"
            % ("{:,}".format(d["particles"]), what, d["size"][0], d["size"][1], SAMPLES,
               "from the cache (time not measured in this run)" if d["reference_seconds"] is None
               else "%.1f s" % d["reference_seconds"], d["threads"], html.escape(str(d["adapter"])),
               len(d["timing"]), d["sweep_wall_seconds"], name))
    out += "<h3>SSIM per channel, %d samples</h3>\n" % SAMPLES + table(name, d)
    out += "<h3>Render time against samples, one line per N (the thesis's figure), and error against time</h3>\n"
    out += '<div class="grid">' + figure(name + "/time.svg", "time against samples (%s)" % name)
    out += figure(name + "/error_time.svg", "1 − SSIM against time (%s)" % name)
    out += figure(name + "/dssim.svg", "1 − SSIM against samples (%s)" % name)
    out += figure(name + "/dssim_baseline.svg", "1 − SSIM against the thesis's GT (%s)" % name) + "</div>\n"
    out += "<h3>Error attribution</h3>\n" + attribution_html(name, d)
    out += "<h3>Images (%d samples)</h3>\n<div class=\"grid\">" % SAMPLES + figure(name + "/reference.png", "exact reference")
    for r in d["rows"]:
        out += figure(r["image"], "thesis N = %s" % r["n_exact"])
    return out + "</div>\n"


CSS = """body{font-family:sans-serif;max-width:1300px;margin:1em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:.5em 0;font-size:13px}td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}
th{background:#eee}.grid{display:flex;flex-wrap:wrap;gap:8px}figure{margin:0}
figure img{image-rendering:pixelated;max-width:640px}figcaption{font-size:12px;max-width:320px}
.grid figure img[src$=".png"]{width:256px}.grid figure img[src$=".svg"]{width:620px}"""


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


def page(data, side, text):
    body = "<h1>The thesis's evaluation (chapter 6), reproduced with pgt</h1>\n"
    body += text
    for name in ("1uun", "random"):
        body += section(name, data[name], side)
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>pgt: the thesis's evaluation</title>"
            "<style>%s</style></head><body data-pgt-images=\"pending\">\n%s%s\n</body></html>\n" % (CSS, body, SCRIPT))


def mean(d, n, key):
    for r in d["rows"]:
        if r["n_exact"] == n and r[key]:
            return r[key]["mean"]
    return None


def shares(d, run):
    """'overlap 17.2 %, sampling 0.0 %, …' of the MSE of one attributed run, largest first."""
    for a in d["attributions"]:
        if a["run"] == run:
            parts = sorted(((c["mse_share"], c["cause"]) for c in a["causes"]), reverse=True)
            text = ", ".join("%s %.3g%%" % (name, 100 * v) for v, name in parts)
            return text + ", interaction %.2g%%" % (100 * a["interaction"])
    return "not measured"


def written(data, side):
    u, r = data["1uun"], data["random"]
    cost = []
    for name, d in (("1UUN", u), ("the random set", r)):
        scale = (512.0 / side) ** 2
        gpu = sum(t["seconds"] for t in d["timing"] if t["method"] == "thesis")
        ref = d["reference_seconds"]
        cost.append("%s: the thesis runs ≈ %.0f s of lavapipe time%s" % (
            name, gpu * scale,
            "" if ref is None else ", the reference ≈ %.0f s" % (ref * scale)))
    text = open(os.path.join(HERE, "comparison.html"), encoding="utf-8").read()
    return text.format(
        side=side, cost="; ".join(cost),
        u1=pct(mean(u, 1, "vs_thesis_gt"), 2), u5=pct(mean(u, 5, "vs_thesis_gt"), 4),
        u1x=pct(mean(u, 1, "vs_exact"), 2), u5x=pct(mean(u, 5, "vs_exact"), 3), uallx=pct(mean(u, "all", "vs_exact"), 3),
        r1=pct(mean(r, 1, "vs_thesis_gt"), 2), r10=pct(mean(r, 10, "vs_thesis_gt"), 4),
        r1x=pct(mean(r, 1, "vs_exact"), 2), r10x=pct(mean(r, 10, "vs_exact"), 3), rallx=pct(mean(r, "all", "vs_exact"), 3),
        adapter=html.escape(str(u["adapter"])), threads=u["threads"],
        au5=shares(u, "thesis samples=100 n_exact=5"), auall=shares(u, "thesis samples=100 n_exact=all"),
        ar5=shares(r, "thesis samples=100 n_exact=5"), arall=shares(r, "thesis samples=100 n_exact=all"))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--side", type=int, required=True)
    args = ap.parse_args()
    data = {name: dataset(name, args.side) for name in ("1uun", "random")}
    tables = {name: {k: v for k, v in d.items() if k not in ("attributions", "timing")} for name, d in data.items()}
    tables["note"] = ("SSIM as fractions. size is what this report was rendered at (the thesis used 512x512); "
                      "gpu_seconds are timestamp-query GPU times on the named adapter; published values are "
                      "the thesis's Tables 6.1/6.2 (against its own GT, N = all).")
    with open(os.path.join(HERE, "tables.json"), "w", encoding="utf-8") as f:
        json.dump(tables, f, indent=2)
        f.write("\n")
    with open(os.path.join(HERE, "index.html"), "w", encoding="utf-8") as f:
        f.write(page(data, args.side, written(data, args.side)))


if __name__ == "__main__":
    main()
