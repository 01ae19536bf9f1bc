"""The report's section on an adaptive sparse grid: which inputs it refined. Per file, a table of the
highest 1-D level and the indices that refine each input, and a picture of the index set (one row
per multi-index, in the order the rounds added them, its 1-D level per input) beside the refined
indices per input."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import plots
from .loading import AnalysedFile, file_name_within
from .blocks import Figure, Section, Table, _rel


def plot_index_set(index_set: dict, parameters: list[str], path: Path, title: str) -> Path:
    """The multi-indices as a level map (rows in the order added, active ones marked) beside the
    number of refined indices that involve each input."""
    levels = np.array(index_set["indices"], dtype=int).reshape(-1, len(parameters))
    height = min(9.0, 1.6 + 0.06 * len(levels))
    fig, (heat, bars) = plots.plt.subplots(1, 2, figsize=(11, height), gridspec_kw={"width_ratios": [3, 2]})
    top_level = max(1, int(levels.max()))
    image = heat.imshow(levels, aspect="auto", cmap=plots.plt.get_cmap("viridis", top_level + 1),
                        interpolation="nearest", vmin=-0.5, vmax=top_level + 0.5)
    heat.set_xticks(range(len(parameters)), parameters, fontsize=8, rotation=45)
    heat.set_ylabel("multi-index, in the order added", fontsize=8)
    heat.tick_params(labelsize=8)
    active = [row for row, old in enumerate(index_set["old"]) if not old]
    heat.plot(np.full(len(active), len(parameters) - 0.5), active, ">", color="red", ms=3, clip_on=False,
              label="active (not refined)")
    heat.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0, -0.12), frameon=False)
    fig.colorbar(image, ax=heat, label="1-D level", ticks=range(top_level + 1))
    refined = np.count_nonzero(levels[np.array(index_set["old"], dtype=bool)] > 0, axis=0)
    bars.barh(range(len(parameters)), refined, color=plots.COLORS[0])
    bars.set_yticks(range(len(parameters)), parameters, fontsize=8)
    bars.invert_yaxis()
    bars.set_xlabel("refined multi-indices involving the input", fontsize=8)
    bars.grid(alpha=0.3, axis="x")
    fig.suptitle(title, fontsize=11)
    return plots._save(fig, path)


def index_set_section(entries: list[AnalysedFile], out_dir: Path) -> Section:
    """For the entries whose file holds an adaptive grid's index set (Statistics.index_set)."""
    blocks, rows, facts = [], [], []
    for entry in entries:
        index_set, parameters = getattr(entry.stats, "index_set", None), entry.stats.parameter_names
        if not index_set:
            continue
        levels = np.array(index_set["indices"], dtype=int).reshape(-1, len(parameters))
        eta = index_set["eta"]
        facts.append(f"{entry.label}: {index_set['rounds']} rounds, {len(levels)} multi-indices, stopped by "
                     f"{index_set['stopped'] or 'nothing yet (interrupted)'}, stopping indicator η = "
                     f"{'n/a' if eta is None else f'{eta:.3g}'} (what the refinement stopped on, not an error "
                     "estimate: it can lie far below the error; each output's validation is the check)")
        old = np.array(index_set["old"], dtype=bool)
        refined = np.count_nonzero(levels[old] > 0, axis=0)
        for k in sorted(range(len(parameters)), key=lambda k: (-refined[k], -int(levels[:, k].max()))):
            rows.append([entry.label, parameters[k], int(refined[k]), int(levels[:, k].max()),
                         int(np.count_nonzero(levels[:, k])),
                         int(np.count_nonzero((levels[:, k] > 0) & (np.count_nonzero(levels, axis=1) > 1)))])
        path = plot_index_set(index_set, parameters, out_dir / "plots" / file_name_within(f"index_set_{entry.stem}.png"),
                              f"Adaptive grid: {entry.label}")
        blocks.append(Figure(_rel(path, out_dir), f"The index set of {entry.label}: each row a multi-index (its "
                                                  "1-D level per input, 0 = the centre point only), in the order "
                                                  "the rounds added them, the active (not refined) ones marked; right, how many "
                                                  "refined indices involve each input."))
    blocks.insert(0, Table("Refinement per input (most refined first)", [
        "file", "input", "refined indices involving it", "highest 1-D level", "indices involving it",
        "of them mixed (with other inputs)"],
        rows, "tables/index_set.csv"))
    return Section("Adaptive grid: the refined inputs", "index-set",
                   "The dimension-adaptive sparse grid (Gerstner–Griebel) refined, round by round, the multi-"
                   "index whose difference rule changed the mean or the variance most (ε_m and ε_v over time of "
                   "every output and quantity). " + "; ".join(facts) + ".", blocks)
