"""The parameter vectors of the kernels by name (engines.compiled.params): every field of a settings'
list is either in its layout, read by a kernel, or listed as not read with a reason; no vector is
read at a literal position."""
import glob
import os
import re

import pytest

from engines.compiled import params
from engines.compiled.layout import Layout
from engines.model.contact import CONTACT_FIELDS
from engines.model.fields import Field

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
COMPILED = os.path.join(ROOT, "engines", "compiled")
VECTORS = ("prm", "_prm", "wp", "tie_prm", "balance", "lam", "totals", "motion")


def kernel_sources():
    """The source text of engines/compiled (its modules and packages)."""
    paths = glob.glob(os.path.join(COMPILED, "**", "*.py"), recursive=True)
    return "\n".join(open(p).read() for p in paths)


def unread(layout, source):
    """The names of ``layout`` no ``LAYOUT.name`` in ``source`` reads."""
    return [n for n in layout.names if not re.search(rf"\b{layout.__name__}\.{n}\b", source)]


@pytest.mark.parametrize("layout", params.PARAMETERS, ids=lambda l: l.__name__)
def test_every_field_in_the_layout_or_listed_as_not_read(layout):
    """Each field of the list is in the layout or in not_read (with its reason), never both; each
    name of the layout is read by a kernel by name."""
    in_layout = [n for n in layout.fields if n in layout.names]
    assert sorted(in_layout + list(layout.not_read)) == sorted(layout.fields)
    assert all(len(why) > 10 for why in layout.not_read.values())
    assert unread(layout, kernel_sources()) == []


def test_a_new_field_no_kernel_reads_is_caught():
    """A field added to the contact settings lands in the layout; no kernel reads it, so the test
    above names it until it is read or listed as not read."""
    fields = {**CONTACT_FIELDS, "cohesion": Field(float, 0.0, None, "a field no kernel reads")}
    layout = Layout.of_fields("CONTACT_PRM", fields, params.CONTACT_PRM.not_read, extra=("dt",))
    assert unread(layout, kernel_sources()) == ["cohesion"]
    with pytest.raises(ValueError, match="cohesion"):
        Layout.of_fields("CONTACT_PRM", CONTACT_FIELDS, {"cohesion": "gone"})


def test_contact_vector_by_name():
    """contact_params puts each setting at its layout position, dt last."""
    from engines.compiled import kernels
    from engines.model.contact import ContactSettings
    s = ContactSettings()
    prm = kernels.contact_params(s, 2e-6)
    assert prm[params.CONTACT_PRM.eps_m] == s.eps_m and prm[params.CONTACT_PRM.kn] == s.kn
    assert prm[params.CONTACT_PRM.dt] == 2e-6 and len(prm) == len(params.CONTACT_PRM.names)


def test_no_vector_read_at_a_literal_position():
    """No ``prm[6]``, ``wp[0]``, ``lam[1]``, ``balance[2]`` ...: read by a layout's name."""
    literal = re.compile(rf"\b({'|'.join(VECTORS)})\[\s*-?\d")
    found = []
    for folder in ("engines/compiled", "engines/model", "engines/yade", "benchmarks"):
        for path in glob.glob(os.path.join(ROOT, folder, "**", "*.py"), recursive=True):
            for k, line in enumerate(open(path), 1):
                if literal.search(line):
                    found.append(f"{os.path.relpath(path, ROOT)}:{k}: {line.strip()}")
    assert found == []
