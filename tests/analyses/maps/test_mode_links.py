"""Mode links (shimmy.analyses.maps.mode_links): a change the follow loses keeps the last point reached, and a
warm map resumes the follow there.

Independent check: the cold map's way, a follow from the slice's own change (its diagram's located change) at
each design, against the record resumed from the nearby design's last point; the record's point relocated
at its own load.
"""

import pytest

from shimmy.analyses.diagrams.mode_changes import relocate
from shimmy.analyses.maps.map_slices import map_slice
from shimmy.analyses.maps.mode_links import LOST, OPEN, LinkPointsUnit, ModeLinksUnit, carried_link
from shimmy.model.configurations import Configuration
from shimmy.model.parameters import Parameters

NES_PD = Configuration.parse("nes_pd")
#: nes_pd's slice loads where the lateral change of 248.7 kN runs down towards a turn in the load near 233.7 kN
FROM, TO = 248659.21787709495, 233743.0167597765


def _link(a_p: float):
    params = Parameters().with_overrides({"a_p": a_p})
    s = map_slice(NES_PD, FROM, params=params, v_range=(1.0, 200.0), n_v=100)
    assert [c.threshold for c in s.mode_changes] == [0.2]
    return params, s, ModeLinksUnit(NES_PD, params, tuple(s.mode_changes), (), TO, False, (0,)).run()[0]


@pytest.mark.slow
def test_a_lost_change_is_resumed_where_its_follow_gave_up():
    """At a_p 0.9 the change (27.67 m/s) is lost on the way down (its curve steepens towards a turn in the load
    just above 233.7 kN): the record keeps the last point reached, a point of the change (it stays where it is
    when relocated at its load). Resumed at the same design it is lost again short of the other load (its own
    steps may take it a little nearer), and carried as lost with that point; at a_p 0.95, where the follow
    from the slice's own change reaches 233.7 kN (an open link), the resumed follow reaches it too and says
    so (None: the link is followed afresh from its slice, as a cold map follows it)."""
    params, s, lost = _link(0.9)
    assert lost.end == LOST and len(lost.points) == 2 and lost.loads == (FROM, TO)
    last = lost.points[-1]
    assert TO < last.Fz < FROM - 10e3 and 40.0 < last.V < 55.0
    again = relocate(last, NES_PD, params)
    assert again is not None and abs(again.V - last.V) <= 1e-6 * last.V
    record = lost.to_dict()
    assert len(record["points"]) == 1 and record["end"] == LOST
    resumed = LinkPointsUnit(NES_PD, params, (record,), False).run()[0]
    assert resumed is not None and len(resumed) == 1 and TO < resumed[0].Fz <= last.Fz
    kept = carried_link(record, resumed, s, type("Slice", (), {"Fz": TO, "mode_changes": []})())
    assert kept.end == LOST and kept.points[-1] is resumed[0]

    params, s, found = _link(0.95)
    assert found.end == OPEN and found.points[-1].Fz == TO
    assert LinkPointsUnit(NES_PD, params, (record,), False).run()[0] is None
