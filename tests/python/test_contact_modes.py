"""Contacts with modes (docs/contact-modes.md) from Python and in batches: the mode, slip, gap and
work_friction columns are in Model.simulate's Result, in nhdyn.simulate_batch and in the CLI's
`nhdyn batch --write-runs` files, the same as `nhdyn simulate`'s CSV; the switch they show is at
the closed form t* = 2 v0 / (7 mu g) of a solid ball thrown sliding without spin."""

import numpy as np
import pytest

import nhdyn
from conftest import read_csv

G, V0, M = 9.81, 3.0, 0.1
MODE_COLUMNS = ["ball_mode", "ball_slip_speed", "ball_slip_x", "ball_slip_y", "ball_slip_z", "ball_gap",
                "work_friction", "impact_loss"]


def t_star(mu):
    return 2 * V0 / (7 * mu * G)


def switch_time(t, mode):
    """The time of the first row where the mode column turns from sliding (1) to rolling (0)."""
    rows = np.nonzero((mode[:-1] == 1) & (mode[1:] == 0))[0]
    assert rows.size == 1, mode
    return t[rows[0] + 1]


def test_python_result_has_the_mode_columns_and_the_switch_at_the_closed_form(examples):
    r = nhdyn.load(examples / "ball_thrown_sliding.toml").simulate()
    for name in MODE_COLUMNS:
        assert name in r.columns["all"] and name in r.columns["contact_forces"]
    mode = r["ball_mode"]
    assert set(np.unique(mode)) == {0.0, 1.0}
    ts = switch_time(r.t, mode)
    assert abs(ts - t_star(0.25)) < 1e-9  # located to round-off; a grid row would be 0.0005 away
    assert [e["name"] for e in r.events] == ["ball_stick"] and abs(r.events[0]["t"] - ts) < 1e-15
    # sliding before (slip falling linearly from v0 to 0), rolling after with no slip
    before, after = r.t < ts, r.t >= ts
    assert np.all(mode[before] == 1) and np.all(mode[after] == 0)
    np.testing.assert_allclose(r["ball_slip_speed"][before], V0 * (1 - r.t[before] / ts), atol=1e-8)
    np.testing.assert_allclose(r["ball_slip_x"][before], r["ball_slip_speed"][before], atol=1e-8)
    assert np.max(np.abs(r["ball_slip_speed"][after])) < 1e-8
    assert np.max(np.abs(r["ball_gap"])) < 1e-10
    assert abs(r["x'"][-1] - 5 * V0 / 7) < 1e-8
    assert abs(r["work_friction"][-1] + M * V0**2 / 7) < 1e-9


def test_python_result_equals_the_cli_csv(examples, cli, tmp_path):
    path = examples / "ball_thrown_sliding.toml"
    r = nhdyn.load(path).simulate()
    cli("simulate", path, "-o", tmp_path / "ball.csv")
    header, values = read_csv(tmp_path / "ball.csv")
    names, table = r.table()
    assert header == names
    np.testing.assert_allclose(values, table, rtol=1e-14, atol=1e-15)


def test_python_batch_carries_the_mode_columns(examples):
    m = nhdyn.load(examples / "ball_thrown_sliding.toml")
    mus = np.array([0.2, 0.25, 0.4])
    batch = nhdyn.simulate_batch(m, parameters={"mu": mus}, threads=2)
    assert batch.ok.all()
    assert list(batch.columns["contact_forces"]) == list(m.simulate(t_end=0.01).columns["contact_forces"])
    for i, mu in enumerate(mus):
        run = m.copy()
        run.parameters["mu"] = mu
        r = run.simulate()
        rows = r.t.size
        t = batch.t[i, :rows]
        assert np.array_equal(t, r.t)
        for name in MODE_COLUMNS + ["ball_N", "x"]:
            assert np.array_equal(batch[name][i, :rows], r[name]), (i, name)
        assert abs(switch_time(t, batch["ball_mode"][i, :rows]) - t_star(mu)) < 1e-9
        assert [e["name"] for e in batch.events[i]] == ["ball_stick"]
    with pytest.raises(KeyError, match="ball_mode"):
        batch["ball_mood"]


def test_dask_batch_carries_the_mode_columns_like_the_local_batch(examples):
    """nhdyn.dask.simulate_batch over two worker processes: the same contact columns (NAME_mode,
    the slip, the gap, work_friction, impact_loss) as nhdyn.simulate_batch, in run order, with the
    switch of each run at its t* (the runs have their own rows: t is runs x rows)."""
    distributed = pytest.importorskip("dask.distributed")
    import nhdyn.dask

    m = nhdyn.load(examples / "ball_thrown_sliding.toml")
    mus = np.array([0.2, 0.25, 0.3, 0.4])
    local = nhdyn.simulate_batch(m, parameters={"mu": mus}, threads=1)
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    client = distributed.Client(cluster)
    try:
        spread = nhdyn.dask.simulate_batch(client, m, parameters={"mu": mus}, chunk_size=1)
    finally:
        client.close()
        cluster.close()
    assert spread.ok.all()
    assert list(spread.columns["contact_forces"]) == list(local.columns["contact_forces"])
    assert spread.contact_forces is not None
    np.testing.assert_array_equal(spread.t, local.t)
    np.testing.assert_array_equal(spread.contact_forces, local.contact_forces)
    for i, mu in enumerate(mus):
        rows = int(np.sum(~np.isnan(spread.t[i])))
        for name in MODE_COLUMNS:
            np.testing.assert_array_equal(spread[name][i, :rows], local[name][i, :rows])
        assert abs(switch_time(spread.t[i, :rows], spread["ball_mode"][i, :rows]) - t_star(mu)) < 1e-9
        assert abs(spread["work_friction"][i, rows - 1] + M * V0**2 / 7) < 1e-9
        assert [e["name"] for e in spread.events[i]] == ["ball_stick"]


def test_cli_batch_run_files_have_the_columns_of_simulate(examples, cli, tmp_path):
    path = examples / "ball_thrown_sliding.toml"
    cli("batch", path, "--grid", "mu=0.2:0.4:3", "--threads", "2", "--write-runs", "-o", tmp_path / "out")
    run_files = sorted((tmp_path / "out").glob("run_*.csv"))
    assert len(run_files) == 3, list((tmp_path / "out").iterdir())
    for i, mu in enumerate([0.2, 0.3, 0.4]):
        cli("simulate", path, "--set", "mu={}".format(mu), "-o", tmp_path / "one.csv")
        header, values = read_csv(tmp_path / "one.csv")
        batch_header, batch_values = read_csv(run_files[i])
        assert batch_header == header
        for name in MODE_COLUMNS:
            assert name in batch_header
        np.testing.assert_allclose(batch_values, values, rtol=1e-14, atol=1e-15)
        t, mode = batch_values[:, 0], batch_values[:, batch_header.index("ball_mode")]
        assert abs(switch_time(t, mode) - t_star(mu)) < 1e-9


def test_plot_draws_the_modes_as_steps_and_the_switch(examples, cli, tmp_path):
    """`--plot`: the gnuplot script (kept by a gnuplot on PATH that copies it, then runs the real
    one) has the steps panel of ball_mode and the mark of ball_stick; the PNG is written."""
    import os
    import shutil
    import subprocess

    real = shutil.which("gnuplot")
    if real is None:
        pytest.skip("gnuplot is not installed")
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    saved = tmp_path / "scripts"
    saved.mkdir()
    fake = bin_dir / "gnuplot"
    fake.write_text('#!/bin/sh\nfor a in "$@"; do [ -f "$a" ] && cp "$a" "{}/$$.gp"; done\nexec {} "$@"\n'.format(
        saved, real))
    fake.chmod(0o755)
    env = dict(os.environ, PATH="{}:{}".format(bin_dir, os.environ.get("PATH", "")))
    png = tmp_path / "ball.png"
    run = subprocess.run([os.environ["NHDYN_CLI"], "simulate", str(examples / "ball_thrown_sliding.toml"), "-o",
                          str(tmp_path / "ball.csv"), "--plot", str(png)], capture_output=True, text=True, env=env)
    assert run.returncode == 0, run.stderr
    assert png.stat().st_size > 1000
    scripts = [p.read_text() for p in saved.glob("*.gp")]
    script = next(s for s in scripts if "multiplot" in s)
    header, _ = read_csv(tmp_path / "ball.csv")
    mode_index = header.index("ball_mode") + 1  # gnuplot counts from 1
    assert "contact modes: 0 rolling, 1 sliding, 2 free" in script
    assert "using 1:{} with steps title 'ball_mode'".format(mode_index) in script
    assert "{:.12f}".format(t_star(0.25))[:12] in script and "event ball_stick" in script


def test_html_report_has_the_modes_panel(examples, cli, tmp_path):
    page = tmp_path / "ball.html"
    cli("simulate", examples / "ball_thrown_sliding.toml", "-o", tmp_path / "ball.csv", "--html", page)
    text = page.read_text()
    assert '"title":"contact modes: 0 rolling, 1 sliding, 2 free","steps":true' in text
    assert '"name":"ball_mode"' in text
    assert "p.steps" in text  # the page's script draws them as steps


@pytest.mark.parametrize("method", ["lagrange", "udwadia-kalaba"])
def test_another_method_is_refused_naming_the_one_to_use(examples, cli, method):
    path = examples / "ball_thrown_sliding.toml"
    run = cli("simulate", path, "--method", method, check=False)
    assert run.returncode == 2, run.stderr
    assert "--method {} cannot solve them".format(method) in run.stderr
    assert "use --method sanh" in run.stderr and "ball-thrown-sliding" in run.stderr
    # Python says it in its own terms (method=...): "method lagrange cannot solve them ... use method sanh"
    with pytest.raises(nhdyn.InputError, match="method {} cannot solve them.*use method sanh".format(method)):
        nhdyn.load(path).simulate(method=method)


PAINLEVE_ROD = """
name = "painleve-rod"
coordinates = ["x", "y", "z", "b"]
gravity = [0, 0, "-g"]
[parameters]
m = 1.0
l = 0.5
rho = 0.01
g = 9.81
b0 = 1.1071487177940904
mu = 1.5
[[frames]]
name = "rod"
translation = ["x", "y", "z"]
rotations = [["y", "b"]]
[[bodies]]
name = "rod"
frame = "rod"
mass = "m"
inertia = ["m*l^2/3", "m*l^2/3", "m*l^2/3"]
[[contacts]]
name = "end"
body = "rod"
shape = { sphere = "rho" }
centre = ["l", 0, 0]
unilateral = true
friction = "mu"
mode = "rolling"
[forces]
b = "-100*t"
[initial]
position = { x = 0, y = 0, z = "l*sin(b0) + rho", b = "b0" }
velocity = { x = 0, y = 0, z = 0, b = 0 }
"""


def test_painleve_during_a_run_exits_1_with_the_partial_rows(cli, tmp_path):
    """A rod on its end tipped by a growing torque would start sliding in Painleve's paradox
    (docs/contact-modes.md): exit 1, the message names the contact and t, the rows before are in
    FILE.partial.csv; with mu below 4/3 it slides on and the run ends normally."""
    model = tmp_path / "rod.toml"
    model.write_text(PAINLEVE_ROD)
    run = cli("simulate", model, "-o", tmp_path / "rod.csv", "--t-end", "0.1", "--output-step", "0.001", check=False)
    assert run.returncode == 1, run.stderr
    assert "contact 'end' slides in Painleve's paradox at t = 0.04" in run.stderr
    assert "Lower the friction coefficient" in run.stderr
    partial = tmp_path / "rod.partial.csv"
    assert partial.exists() and not (tmp_path / "rod.csv").exists()
    rows = [line for line in partial.read_text().splitlines() if line and not line.startswith("#")]
    assert len(rows) > 40  # a header and the rows up to t = 0.04
    ok = cli("simulate", model, "--set", "mu=1.2", "-o", tmp_path / "slides.csv", "--t-end", "0.1")
    assert "end_slip" in ok.stdout and "Painleve" not in ok.stderr
