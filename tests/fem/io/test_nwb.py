"""NWB output of a traced experiment's afferents (fem.io.nwb): spike times, afferents and the
stimulus read back with pynwb; the same run writes the same bytes; without pynwb a scene asking
for it is refused before anything runs."""
import hashlib

import numpy as np
import pytest

import pipeline
from fem.experiments.scene import Scene
from fem.io import nwb
from fem.receptors.afferents import Population, PopulationResponse
from fingertip.errors import InputError
from tests.helpers import ROOT

pynwb = pytest.importorskip("pynwb")


def _response() -> PopulationResponse:
    pop = Population(np.array(["SA1", "RA", "PC"], dtype=object), np.array([3, 0, 2]), np.arange(3),
                     np.array([[0.5, 6.0, -1.0], [1.0, 6.1, 0.0], [-0.25, 5.9, 2.0]]), np.tile([0.0, 1.0, 0.0], (3, 1)),
                     np.array([0.3, 1.6, 2.0]))
    t = np.linspace(0.0, 0.7, 15)
    spikes = [np.array([0.0123456, 0.25, 0.6999998]), np.zeros(0), np.array([1 / 3])]
    return PopulationResponse(pop, t, np.zeros((3, 15)), np.zeros((3, 15)), spikes)


def test_round_trip_and_same_bytes(tmp_path):
    resp = _response()
    depth, force = np.interp(resp.times_s, [0, 0.1, 0.6, 0.7], [0, 1, 1, 0]), np.linspace(0, 0.1, 15)
    for name in ("a.nwb", "b.nwb"):
        nwb.write_nwb(tmp_path / name, "ramp_hold", resp, depth, force)
    digest = [hashlib.sha256((tmp_path / n).read_bytes()).hexdigest() for n in ("a.nwb", "b.nwb")]
    assert digest[0] == digest[1]
    with pynwb.NWBHDF5IO(str(tmp_path / "a.nwb"), "r") as io:
        f = io.read()
        units = f.units
        assert list(units["afferent_class"][:]) == ["SA1", "RA", "PC"]
        assert list(units["model_index"][:]) == [3, 0, 2]
        for i, mine in enumerate(resp.spikes):
            assert np.abs(np.asarray(units["spike_times"][i]) - mine).max(initial=0.0) < 1e-6
            assert units["x_mm"][i] == resp.population.site_mm[i, 0] and units["depth_mm"][i] == resp.population.depth_mm[i]
        stim = f.stimulus["indentation_depth"]
        assert np.array_equal(stim.data[:], depth) and stim.conversion == 1e-3
        assert np.array_equal(stim.timestamps[:], resp.times_s)
        assert np.array_equal(f.stimulus["contact_force"].data[:], force)


def test_without_pynwb_the_scene_is_refused(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(nwb, "installed", lambda: False)
    with pytest.raises(InputError, match=r'pip install -e "\.\[nwb\]"'):
        Scene.from_dict({"afferents": {"nwb": True},
                         "experiment": [{"indentor": "punch:2", "depth_mm": 1.0, "trace": {}}]})
    out = tmp_path / "run"
    code = pipeline.main(["indent", str(tmp_path), "--scene", str(ROOT / "scenes" / "ramp_hold_viscoelastic.toml"),
                          "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("error:") and nwb.INSTALL in err[0] and not out.exists()
