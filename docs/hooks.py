"""MkDocs hook (mkdocs.yml `hooks:`): the campaign-key reference generated from the code at every build."""
from __future__ import annotations

from mkdocs.structure.files import File

KEYS_PAGE = "reference/campaign-keys.md"


def on_files(files, config):
    """The key reference from the code, in place of the committed copy (which tests/test_docs.py keeps
    equal to it: `python -m uqflight.campaign.keys > docs/reference/campaign-keys.md` rewrites it)."""
    from uqflight.campaign.keys import reference_page

    committed = files.get_file_from_path(KEYS_PAGE)
    if committed is not None:
        files.remove(committed)
    files.append(File.generated(config, KEYS_PAGE, content=reference_page()))
    return files
