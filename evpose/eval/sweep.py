"""Parameter sweeps: a grid over config fields x recordings -> a table of metrics and the best configuration.

Grid items name fields by dotted paths into the target's config dataclass
(``noise_filter.window_us=[1000,3000]`` for the tracker); values are YAML, a
list for several values. The grid expands in the order given (last item varies
fastest). Each (configuration, recording) pair is one job; the table averages
the score over recordings; the best configuration (all its recordings
succeeded, best mean score) is written as a complete config file.
"""

from __future__ import annotations

import copy
import itertools
import json
from dataclasses import dataclass
from pathlib import Path

from evpose.errors import ConfigError
from evpose.eval.cache import Job, ResultCache
from evpose.eval.recordings import label
from evpose.eval.runner import RunnerConfig, resolve, run_jobs
from evpose.io.atomic import atomic_path, output_set


@dataclass(frozen=True)
class SweepTarget:
    """What a sweep varies and runs."""

    config_class: str
    """The config dataclass as ``"module:Class"``."""
    job_fn: str
    """The job as ``"module:function"``, called with ``config`` (nested dict) and ``recording`` (spec)."""
    score: str
    """Default metric (key of the job's ``metrics``) that ranks configurations."""
    minimize: bool
    """True when a lower score is better."""
    metrics: tuple[str, ...]
    """The metrics the job returns, any of which ``--score`` may name (checked before the jobs run)."""


TARGETS: dict[str, SweepTarget] = {
    "tracking": SweepTarget("evpose.tracker.config:TrackerConfig", "evpose.eval.suite:tracking_job", "ate_mean_m", True,
                            ("are_mean_deg", "ate_mean_m", "filtered_share", "ok_share", "rre_mean_deg", "rte_mean_m")),
    "noise-filter": SweepTarget("evpose.frontend.noise_filter:NoiseFilterConfig", "evpose.eval.jobs:noise_filter_job", "kept_share", False,
                                ("events", "events_kept", "kept_share")),
}


def parse_grid(items: list[str]) -> dict[str, list]:
    """``["a.b=[1,2]", "c=x"]`` -> ``{"a.b": [1, 2], "c": ["x"]}`` (values parsed as YAML)."""
    import yaml

    grid: dict[str, list] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise ConfigError(f"grid item {item!r}: expected FIELD=VALUES, e.g. noise_filter.window_us=[1000,3000]")
        try:
            values = yaml.safe_load(text)
        except yaml.YAMLError:
            raise ConfigError(f"grid item {item!r}: values are not valid YAML") from None
        values = values if isinstance(values, list) else [values]
        if not values:
            raise ConfigError(f"grid item {item!r}: no values")
        if name in grid:
            raise ConfigError(f"grid item {item!r}: field {name} given twice")
        grid[name] = values
    return grid


def expand_grid(grid: dict[str, list]) -> list[dict]:
    """Every combination of the grid's values, as ``{dotted name: value}`` dicts."""
    names = list(grid)
    return [dict(zip(names, combo)) for combo in itertools.product(*(grid[n] for n in names))]


def apply_overrides(base: dict, overrides: dict) -> dict:
    """A copy of the nested config dict ``base`` with dotted-path ``overrides`` set; unknown fields are an error."""
    out = copy.deepcopy(base)
    for dotted, value in overrides.items():
        node = out
        parts = dotted.split(".")
        for depth, part in enumerate(parts):
            if not isinstance(node, dict) or part not in node:
                where = ".".join(parts[:depth]) or "the config"
                known = ", ".join(sorted(node)) if isinstance(node, dict) else "none (not a group)"
                raise ConfigError(f"unknown config field {dotted!r}: {where} has no {part!r} (known: {known})")
            if depth == len(parts) - 1:
                if isinstance(node[part], dict):
                    raise ConfigError(f"config field {dotted!r} is a group; name one of its fields")
                node[part] = value
            else:
                node = node[part]
    return out


def build_configs(target: SweepTarget, grid: dict[str, list], base: dict | None = None) -> list[tuple[dict, dict]]:
    """(overrides, full config dict) per grid point; each is validated by building the dataclass."""
    from evpose.tracker.config import config_from_dict, config_to_dict

    cls = resolve(target.config_class)
    base = config_to_dict(cls()) if base is None else base
    out = []
    for overrides in expand_grid(grid):
        full = apply_overrides(base, overrides)
        # Round trip through the dataclass: checks types and canonicalises (e.g. 1000 -> 1000.0 for floats).
        full = config_to_dict(config_from_dict(cls, full, source="sweep grid"))
        out.append((overrides, full))
    return out


def sweep_jobs(target: SweepTarget, configs: list[tuple[dict, dict]], recordings: list[str]) -> list[Job]:
    return [Job(f"c{ci:03d}/{label(rec)}", target.job_fn, {"config": full, "recording": rec}) for ci, (_, full) in enumerate(configs) for rec in recordings]


def sweep_table(configs: list[tuple[dict, dict]], recordings: list[str], outcomes: list[dict], score: str, minimize: bool) -> dict:
    """The deterministic part of a sweep: per configuration its overrides, per-recording metrics and mean score."""
    rows = []
    k = 0
    for ci, (overrides, _) in enumerate(configs):
        per_rec = {}
        scores = []
        failed = []
        for rec in recordings:
            out = outcomes[k]
            k += 1
            if out["ok"]:
                metrics = out["result"]["metrics"]
                per_rec[rec] = metrics
                if score not in metrics:
                    raise ConfigError(f"score {score!r} is not a metric of this sweep (metrics: {', '.join(sorted(metrics))})")
                scores.append(float(metrics[score]))
            else:
                per_rec[rec] = {"error": out["error"]}
                failed.append(rec)
        mean = sum(scores) / len(scores) if scores and not failed else None
        rows.append({"config": ci, "overrides": overrides, "mean_score": mean, "failed": failed, "recordings": per_rec})
    ranked = [r for r in rows if r["mean_score"] is not None]
    best = None
    if ranked:
        # Ties go to the earlier configuration (stable, deterministic).
        best = (min if minimize else max)(ranked, key=lambda r: r["mean_score"])["config"]
    return {"score": score, "minimize": minimize, "recordings": recordings, "rows": rows, "best": best}


def markdown_table(table: dict) -> str:
    """The sweep table as Markdown (one row per configuration, one score column per recording)."""
    recs = table["recordings"]
    head = ["#", "overrides"] + [label(r) for r in recs] + [f"mean {table['score']}"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in table["rows"]:
        cells = [str(row["config"]), ", ".join(f"{k}={v}" for k, v in row["overrides"].items())]
        for r in recs:
            m = row["recordings"][r]
            cells.append("failed" if "error" in m else f"{m[table['score']]:.6g}")
        cells.append("-" if row["mean_score"] is None else f"{row['mean_score']:.6g}")
        if row["config"] == table["best"]:
            cells[0] = f"**{cells[0]}** (best)"
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


@dataclass
class SweepOutput:
    table: dict
    """Deterministic table (see :func:`sweep_table`)."""
    timing: list[dict]
    """Per job: name and its measured timing (not deterministic)."""
    best_config: dict | None
    """The best full configuration as a nested dict, or None if every configuration failed."""


def run_sweep(target_name: str, grid_items: list[str], recordings: list[str], out_dir: str | Path, runner: RunnerConfig = RunnerConfig(), score: str | None = None, minimize: bool | None = None) -> SweepOutput:
    """Run the sweep, resuming from ``out_dir/jobs``; writes ``sweep.json``, ``sweep.md`` and ``best_config.yaml``."""
    if target_name not in TARGETS:
        raise ConfigError(f"unknown sweep target {target_name!r} (known: {', '.join(TARGETS)})")
    if not recordings:
        raise ConfigError("a sweep needs at least one recording")
    target = TARGETS[target_name]
    if score is not None and score not in target.metrics:
        # Checked only once every job had run (minutes of work, and OUT/jobs written) before.
        raise ConfigError(f"score {score!r} is not a metric of this sweep (metrics: {', '.join(target.metrics)})")
    configs = build_configs(target, parse_grid(grid_items))
    jobs = sweep_jobs(target, configs, recordings)
    out_dir = Path(out_dir)
    outcomes = run_jobs(jobs, ResultCache(out_dir / "jobs"), runner, desc="sweep")
    table = sweep_table(configs, recordings, outcomes, score or target.score, target.minimize if minimize is None else minimize)
    timing = [{"job": j.name, **(o["result"].get("timing", {}) if o["ok"] else {})} for j, o in zip(jobs, outcomes)]
    best = configs[table["best"]][1] if table["best"] is not None else None
    out_dir.mkdir(parents=True, exist_ok=True)
    # The three files appear together; without a best configuration an earlier sweep's one would pass for this one's.
    stale = out_dir / "best_config.yaml"
    with output_set(remove=(stale,) if best is None and stale.is_file() else ()):
        with atomic_path(out_dir / "sweep.json") as tmp:
            tmp.write_text(json.dumps({"target": target_name, "grid": grid_items, "table": table, "timing": timing}, indent=2) + "\n")
        with atomic_path(out_dir / "sweep.md") as tmp:
            tmp.write_text(f"# Sweep: {target_name}\n\nScore: `{table['score']}` ({'lower' if table['minimize'] else 'higher'} is better), mean over recordings.\n\n" + markdown_table(table))
        if best is not None:
            import yaml

            with atomic_path(out_dir / "best_config.yaml") as tmp:
                tmp.write_text(yaml.safe_dump(best, sort_keys=False))
    return SweepOutput(table, timing, best)
