#!/usr/bin/env python3
"""Writes docs/figures.md from the JSON that tools/figures stored in docs/figures/.

usage: tools/figures_render.py FIGURES_DIR OUT.md

Each figure gets a table: what the value measures, the goal it is held to (where there is one)
and the value measured; an evaluation's breakdowns follow as tables of their own (per preset, per
kind, the verdicts, the confusion of kinds, the drop-offs), then every other number of its JSON.
Standard library only.
"""
import json
import os
import sys

# bench perception's drop-off stage, timed on its own on the same frames (both perception figures).
DROP_STAGE_ROWS = [
    ("ours_drop_median_ms", "drop stage, median per frame (wall)", "", "ms"),
    ("ours_drop_cpu_median_ms", "drop stage, median per frame (CPU)", "", "ms"),
    ("drop_share", "drop stage / ours (median wall time)", "", "ratio"),
    ("drop_cpu_share", "drop stage / ours (median CPU time)", "", "ratio"),
]


def perception_rows(ms_goal):
    """bench perception's rows: ours against the PCL reference, then the drop stage on its own."""
    return [("ours_median_ms", "ours, median per frame (wall)", ms_goal, "ms"),
            ("ours_cpu_median_ms", "ours, median per frame (CPU)", ms_goal, "ms"),
            ("ours_p95_ms", "ours, 95th percentile (wall)", "", "ms"),
            ("reference_median_ms", "PCL reference, median per frame (wall)", "", "ms"),
            ("reference_cpu_median_ms", "PCL reference, median per frame (CPU)", "", "ms"),
            ("ratio", "reference / ours (median wall time)", ">= 8x", "x"),
            ("cpu_ratio", "reference / ours (median CPU time)", "", "x")] + DROP_STAGE_ROWS


# name: (title, what the run measures, [(JSON key, what it means, goal, unit)])
# unit: "ms", "m->cm" (metres shown in cm), "m->mm", "ratio" (a share shown as %), "x", "" (as is)
FIGURES = [
    ("bench-perception", "Perception speed, synthetic frames",
     "Plane segmentation, floor, Manhattan frame and classification on 32 synthetic 640x480 frames, "
     "one thread; the reference is the paper's PCL pipeline (voxel grid, normals, region growing, "
     "RANSAC, clusters) on the same frames in the same process, taking turns frame by frame.",
     perception_rows("")),
    ("bench-perception-kitchen", "Perception speed, real Kinect frames",
     "The same benchmark on 32 frames of the real 7-Scenes kitchen (../shared/data).",
     perception_rows("<= 8 ms")),
    ("bench-stairs", "Stair detection and modelling speed",
     "The stairs stage (detection + modelling) per frame on the synthetic presets, perception run "
     "beforehand and not timed; the reference is the paper's stair stage configuration.",
     [("median_ms", "ours, median per frame", "<= 2 ms (paper: 7 ms)", "ms"),
      ("p95_ms", "ours, 95th percentile", "", "ms"),
      ("reference_median_ms", "reference, median per frame", "", "ms"),
      ("ratio", "reference / ours", "", "x")]),
    ("bench-traversal", "Traversal tracker speed",
     "The traversal tracker's thread-CPU time per frame on the 8-step climb and descent (ground-truth "
     "poses as the odometry); the reference is the stairs stage on the same frames.",
     [("median_ms", "tracker, median per frame", "<= 1 ms", "ms"),
      ("p95_ms", "tracker, 95th percentile", "", "ms"),
      ("holding_median_ms", "median on frames with a staircase held", "", "ms"),
      ("reference_median_ms", "stairs stage, median per frame", "", "ms")]),
    ("eval-synthetic", "Stair detection, synthetic views",
     "stairguide eval on 16 views each of six static presets (ascending, descending, single step, "
     "people on the stairs, a table, a corridor), seed 5: detections scored against the renderer's "
     "truth.",
     [("fp", "false positives (stair-free views reported)", "0", ""),
      ("recall_fully_visible", "recall, >= 2 steps fully visible", ">= 99%", "ratio"),
      ("recall", "recall, every view with a staircase", "", "ratio"),
      ("precision", "precision", "", "ratio"),
      ("riser_err_mean_m", "riser error, mean", "<= 1 cm", "m->cm"),
      ("tread_err_mean_m", "tread error, mean", "<= 1 cm", "m->cm"),
      ("width_err_mean_m", "width error, mean (both ends visible)", "<= 5 cm", "m->cm"),
      ("edge_pos_err_mean_m", "first-edge position error, mean", "<= 3 cm", "m->cm"),
      ("yaw_err_mean_deg", "first-edge yaw error, mean", "<= 2 deg", "deg")]),
    ("eval-world", "Stair detection, the world's flights through real sensor artefacts",
     "stairguide eval on 24 views each of the world-range presets (risers 10-22 cm, treads >= 20 cm) "
     "through a Kinect v1's artefacts (seed 303) and a Kinect v2's (seed 304), seeds nothing was "
     "tuned on.",
     [("fp", "false positives", "0", ""),
      ("recall_fully_visible", "recall, >= 2 steps fully visible", ">= 98%", "ratio"),
      ("recall", "recall, every view with a staircase", "", "ratio"),
      ("riser_err_mean_m", "riser error, mean", "<= 1 cm", "m->cm"),
      ("tread_err_mean_m", "tread error, mean", "<= 1 cm", "m->cm")]),
    ("eval-world2", "Stair detection, the second world (issue 39's structures)",
     "stairguide eval on 24 views each of the second world's presets, seed 801 (never tuned on), "
     "Kinect v1 artefacts: flights rising beside a landing (turn), low risers, steep goings, carpet "
     "and things on the steps (dressed), the wearer's legs in view, waist cameras (lowrig); and six "
     "stair-free scenes (shelves, boxes, sofa, bench, low table, bed). Per preset in by_scene.",
     [("fp", "false positives and misplaced detections", "0", ""),
      ("recall_fully_visible", "recall, >= 2 steps fully visible", ">= 99%", "ratio"),
      ("recall", "recall, every view with a staircase", "", "ratio"),
      ("riser_err_mean_m", "riser error, mean", "<= 1 cm", "m->cm"),
      ("tread_err_mean_m", "tread error, mean", "<= 1 cm", "m->cm")]),
    ("standing-wearer", "A wearer standing still at a staircase, any rig",
     "tools/standing-wearer: rigs 0.5-1.8 m x 15-80 deg (20), the world's flights up and down and "
     "the waist-camera flights, seeds 4301-4302, 3 views each; the daemon's perception stage sees "
     "one view 30 times through fresh noise, nothing learned before.",
     [("told_share", "pairs with the floor and the flight, placed, within 30 frames", ">= 98%", "ratio"),
      ("pairs", "(rig, flight) pairs with >= 2 steps in view", "", ""),
      ("first_frame_max", "latest first frame among those told", "< 30", "")]),
    ("eval-real", "Stair detection, labelled real frames",
     "stairguide eval on ../shared/data/labels.csv: real Kinect clouds and frames labelled by hand "
     "(stairs and stair-free scenes).",
     [("frames", "frames scored", "", ""),
      ("fp", "false positives (stair-free frames reported)", "0", ""),
      ("tp", "staircases found", "", ""),
      ("fn", "staircases missed", "", ""),
      ("precision", "precision", "", "ratio"),
      ("recall", "recall", "", "ratio")]),
    ("eval-odometry-kitchen", "Odometry, real kitchen",
     "stairguide eval-odometry on the real 7-Scenes kitchen (300 frames, hand-held): relative pose "
     "error over 1 s and absolute trajectory error after alignment, ours and OpenCV's RgbdOdometry in "
     "the same run.",
     [("ours.rpe_trans_rmse_m_s", "ours, RPE translation (RMSE over 1 s)", "no worse than the reference", "m->cm"),
      ("reference.rpe_trans_rmse_m_s", "OpenCV RgbdOdometry, RPE translation", "", "m->cm"),
      ("ours.ate_rmse_m", "ours, ATE (RMSE)", "", "m->mm"),
      ("reference.ate_rmse_m", "OpenCV RgbdOdometry, ATE", "", "m->mm"),
      ("ours.median_ms", "ours, median per frame (wall)", "", "ms"),
      ("ours.median_cpu_ms", "ours, median per frame (CPU)", "", "ms"),
      ("reference.median_ms", "OpenCV RgbdOdometry, median per frame (wall)", "", "ms"),
      ("reference.median_cpu_ms", "OpenCV RgbdOdometry, median per frame (CPU)", "", "ms")]),
    ("eval-traversal", "Traversal: which step, how many left, the last one",
     "The ten synthetic walks (climbs and descents of 3, 8 and 14 steps, pausing and turning, past a "
     "person) replayed through the daemon's pipeline (stairguide replay, our own odometry), scored "
     "with stairguide eval-traversal against each frame's truth.",
     [("sequences", "walks", "", ""),
      ("frames_on_stairs", "frames with the user on the flight", "", ""),
      ("step_index_accuracy", "step under the body right", ">= 98%", "ratio"),
      ("count_exact", "walks whose final count is exact", "every walk (10)", ""),
      ("phantom_steps", "frames with a step that is not there", "0", ""),
      ("missed_last_step", "walks whose last step was not announced before it", "0", ""),
      ("gap_corrected_max_m", "largest gap to the truth at a step, corrected", "<= 3 cm", "m->cm"),
      ("fused_riser_err_m", "riser error, fused over frames", "below single frames", "m->cm"),
      ("single_frame_riser_err_m", "riser error, single frames", "", "m->cm"),
      ("fused_tread_err_m", "tread error, fused over frames", "below single frames", "m->cm"),
      ("single_frame_tread_err_m", "tread error, single frames", "", "m->cm")]),
    ("eval-traversal-drift", "Traversal with odometry drift injected",
     "The 8-step climb replayed with 2% scale error and 1 deg/s yaw injected into the odometry "
     "(stairguide replay --drift 2,1): the live view's correction against the odometry alone.",
     [("step_index_accuracy", "step under the body right", ">= 98%", "ratio"),
      ("count_exact", "final count exact", "1", ""),
      ("gap_corrected_max_m", "largest gap at a step, corrected", "<= 3 cm", "m->cm"),
      ("gap_uncorrected_max_m", "largest gap at a step, odometry only", "> 10 cm (paper)", "m->cm")]),
]


def lookup(obj, path):
    for part in path.split("."):
        if not isinstance(obj, dict) or part not in obj:
            return None
        obj = obj[part]
    return obj


def show(v, unit):
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if not isinstance(v, (int, float)):
        return str(v)
    if unit == "ms":
        return f"{v:.3g} ms" if abs(v) < 1 else f"{v:.1f} ms"
    if unit == "m->cm":
        return f"{100 * v:.2f} cm"
    if unit == "m->mm":
        return f"{1000 * v:.1f} mm"
    if unit == "ratio":
        return f"{100 * v:.1f}%"
    if unit == "x":
        return f"{v:.1f}x"
    if unit == "deg":
        return f"{v:.2f} deg"
    if isinstance(v, float) and not v.is_integer():
        return f"{v:.4g}"
    return str(int(v)) if isinstance(v, float) else str(v)


def scalars(obj, prefix=""):
    """Every number or string of a JSON object, as (dotted key, value)."""
    out = []
    if isinstance(obj, dict):
        for k in sorted(obj):
            out += scalars(obj[k], f"{prefix}{k}.")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            out += scalars(v, f"{prefix}{i}.")
    else:
        out.append((prefix[:-1], obj))
    return out


# An evaluation's breakdowns (stairguide eval --json), each shown as a table of its own rather
# than among "every value": per preset or labelled set, per kind of staircase, why each frame was
# decided as it was, what was taken for what, and the drop-offs.
BREAKDOWNS = ("by_scene", "by_kind", "verdicts", "confusion", "drops")
DETECTION_COLUMNS = [("frames", "frames", ""), ("tp", "TP", ""), ("fp", "FP", ""), ("fn", "FN", ""),
                     ("tn", "TN", ""), ("recall_fully_visible", "recall, >= 2 steps", "ratio"),
                     ("riser_err_mean_m", "riser err", "m->cm"), ("tread_err_mean_m", "tread err", "m->cm")]


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return out


def detection_table(title, groups):
    """One row per preset (or kind): the detection counts and errors."""
    def cell(g, key, unit):
        # A share or a mean over no frames is not a figure: shown as "-".
        if key == "recall_fully_visible" and not g.get("fully_visible_frames"):
            return "-"
        if key.endswith("_mean_m") and not g.get(key.replace("_mean_m", "_n")):
            return "-"
        return show(g.get(key), unit)
    rows = [[f"`{name}`"] + [cell(g, k, u) for k, _, u in DETECTION_COLUMNS] for name, g in sorted(groups.items())]
    return ["", f"**{title}**", ""] + table([""] + [c for _, c, _ in DETECTION_COLUMNS], rows)


def verdict_table(verdicts):
    """Why each frame was decided as it was: the detector's verdict, by outcome (TP, FP, FN, TN)."""
    outcomes = [o for o in ("TP", "FP", "FN", "TN") if o in verdicts]
    names = sorted({v for o in outcomes for v in verdicts[o]})
    rows = [[v] + [str(verdicts[o].get(v, 0)) for o in outcomes] for v in names]
    return ["", "**Why each frame was decided so (the verdicts)**", ""] + table(["verdict"] + outcomes, rows)


def confusion_table(confusion):
    """Rows: the true kind; columns: the kind reported."""
    said = sorted({k for row in confusion.values() for k in row})
    rows = [[f"{truth}"] + [str(confusion[truth].get(k, 0)) for k in said] for truth in sorted(confusion)]
    return ["", "**Kind reported (columns) for each true kind (rows)**", ""] + table(["truth"] + said, rows)


def drops_line(drops):
    """The drop-off stage on the same views: told near a drop, silent elsewhere."""
    near, told = drops.get("near", 0), drops.get("near_told", 0)
    none, none_told = drops.get("none", 0), drops.get("none_told", 0)
    return ["", f"**Drop-offs on the same views:** told on {told} of {near} frames with a drop within "
            f"{show(drops.get('near_m'), '')} m; said on {none_told} of {none} frames with no drop and no descent."]


def breakdowns(result):
    out = []
    if isinstance(result.get("by_scene"), dict):
        out += detection_table("Per preset", result["by_scene"])
    if isinstance(result.get("by_kind"), dict):
        out += detection_table("Per kind of staircase", result["by_kind"])
    if isinstance(result.get("verdicts"), dict):
        out += verdict_table(result["verdicts"])
    if isinstance(result.get("confusion"), dict):
        out += confusion_table(result["confusion"])
    if isinstance(result.get("drops"), dict):
        out += drops_line(result["drops"])
    return out


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    src, dst = sys.argv[1], sys.argv[2]
    machine = {}
    if os.path.exists(os.path.join(src, "machine.json")):
        machine = json.load(open(os.path.join(src, "machine.json")))
    lines = [
        "# Figures",
        "",
        "Written by `tools/figures` from the JSON the benchmarks and evaluations print (stored beside this "
        "file in `docs/figures/`); do not edit by hand. `tools/figures` measures them again (about 10 "
        "minutes), `tools/figures --render-only` rewrites this page from the stored JSON.",
        "",
        f"Measured {machine.get('date', '?')} on {machine.get('cpu', '?')} ({machine.get('cores', '?')} cores, "
        f"{machine.get('system', '?')}), {machine.get('build', 'Release')} build of commit "
        f"`{machine.get('commit', '?')}`, load {machine.get('load_1min_at_end', '?')} at the end of the run. "
        "Times depend on the machine and its load (wall times most: on a loaded machine the CPU times are the "
        "stage's own cost); the benchmarks give ratios against a reference run in the "
        "same process on the same frames, which move much less. Synthetic figures come from fixed seeds and "
        "repeat exactly.",
        "",
    ]
    missing = []
    for name, title, what, rows in FIGURES:
        path = os.path.join(src, name + ".json")
        if not os.path.exists(path):
            missing.append(name)
            continue
        stored = json.load(open(path))
        result = stored.get("result", stored)
        lines += [f"## {title}", "", what, "", f"`{stored.get('command', '?')}` ({stored.get('seconds', '?')} s)", ""]
        lines += ["| figure | goal | measured |", "|---|---|---|"]
        shown = set()
        for key, meaning, goal, unit in rows:
            v = lookup(result, key)
            if v is None:
                continue
            shown.add(key)
            lines.append(f"| {meaning} | {goal or '-'} | {show(v, unit)} |")
        lines += breakdowns(result)
        rest = [(k, v) for k, v in scalars({k: v for k, v in result.items() if k not in BREAKDOWNS})
                if k not in shown]
        if rest:
            lines += ["", "<details><summary>every value of the JSON</summary>", "",
                      ", ".join(f"`{k}` {show(v, '')}" for k, v in rest), "", "</details>"]
        lines.append("")
    if missing:
        lines += ["## Not measured", "",
                  "No stored JSON for: " + ", ".join(f"`{m}`" for m in missing) +
                  " (the shared data was absent, or the run failed).", ""]
    with open(dst, "w") as f:
        f.write("\n".join(lines))
    print(f"tools/figures: wrote {dst} from {len(FIGURES) - len(missing)} figures")


if __name__ == "__main__":
    main()
