"""Every relative Markdown link of the README and the documentation's pages points at a file of the repository,
so that it works where a reader meets it: on the built site and in the repository alike.

A page that must point at something only the site's build writes (the gallery, a generated page, a viewer
page) uses a Sphinx role ({doc}, {download}), which the repository shows as text rather than as a broken link.
"""

from __future__ import annotations

import re

import pytest
from support.paths import ROOT
from test_docs_commands import GENERATED, PAGES

#: [text](target) outside code; targets with a scheme (https:, mailto:) or only an anchor are not files
_LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)")


def _links(path):
    text = re.sub(r"```.*?```", "", path.read_text(), flags=re.S)  # code blocks
    text = re.sub(r"`[^`\n]*`", "", text)  # inline code and roles' targets
    for target in _LINK.findall(text):
        if re.match(r"^[a-z]+:", target) or target.startswith("#"):
            continue
        yield target.split("#")[0]


LINKS = [(page, target) for page in PAGES for target in _links(page)]


def test_the_pages_have_relative_links():
    assert len(LINKS) >= 20


@pytest.mark.parametrize("page, target", LINKS, ids=[f"{p.relative_to(ROOT)}->{t}" for p, t in LINKS])
def test_every_relative_link_points_at_a_file_of_the_repository(page, target):
    path = (page.parent / target).resolve()
    generated = any(path == g or g in path.parents for g in GENERATED)  # there only after a site build
    assert path.exists() and not generated, f"{page.relative_to(ROOT)}: [..]({target}) points at nothing in the repository"
