"""MkDocs hooks (mkdocs.yml `hooks:`): the campaign-key reference generated from the code at every
build, and a nav that names pages still being written elsewhere without failing the strict build."""
from __future__ import annotations

from pathlib import Path

from mkdocs.structure.files import File

# Pages of the nav that may be absent from a checkout (written on other branches): dropped from the
# nav while absent. Any other nav entry to a missing file still fails `mkdocs build --strict`.
OPTIONAL_PAGES = {"commands.md", "designs.md", "methods.md", "dependence.md", "report.md", "plots.md",
                  "performance.md"}
KEYS_PAGE = "reference/campaign-keys.md"


def _present(nav, docs: Path):
    kept = []
    for item in nav:
        if isinstance(item, dict):
            (title, value), = item.items()
            if isinstance(value, list):
                value = _present(value, docs)
                if value:
                    kept.append({title: value})
            elif not (value in OPTIONAL_PAGES and not (docs / value).is_file()):
                kept.append(item)
        elif not (item in OPTIONAL_PAGES and not (docs / item).is_file()):
            kept.append(item)
    return kept


def on_config(config):
    config["nav"] = _present(config["nav"], Path(config["docs_dir"]))
    return config


def on_files(files, config):
    """The key reference from the code, in place of the committed copy (which tests/test_docs.py keeps
    equal to it: `python -m uqflight.campaign.keys > docs/reference/campaign-keys.md` rewrites it)."""
    from uqflight.campaign.keys import reference_page

    committed = files.get_file_from_path(KEYS_PAGE)
    if committed is not None:
        files.remove(committed)
    files.append(File.generated(config, KEYS_PAGE, content=reference_page()))
    return files
