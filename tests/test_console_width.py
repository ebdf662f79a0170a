"""Output written to a log (not a terminal) is LOG_WIDTH columns wide, so that `bipedal select`'s
table keeps run names whole in a `nohup` log; COLUMNS still decides when it is set."""

from bipedal_cli.cli_common import LOG_WIDTH, make_console


def test_a_log_is_wider_than_rich_s_80_columns(monkeypatch):
    monkeypatch.delenv("COLUMNS", raising=False)
    console = make_console()  # pytest captures stdout: not a terminal
    assert not console.is_terminal
    assert console.width == LOG_WIDTH


def test_columns_decides_when_set(monkeypatch):
    monkeypatch.setenv("COLUMNS", "90")
    assert make_console().width == 90
