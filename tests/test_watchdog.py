"""The report's watchdog: a silent run ends with a message, a beating one does not."""

import time

from hfcdem.reproduce.watchdog import Watchdog


def test_a_silent_run_is_ended_with_the_case_named():
    heard: list[str] = []
    with Watchdog(0.2, on_expire=heard.append, poll_s=0.02) as dog:
        dog.beat("case kgd (results/r/cases/kgd)")
        time.sleep(0.6)
    assert dog.expired and len(heard) == 1  # once, not at every poll
    assert "case kgd" in heard[0] and "no progress" in heard[0] and "resume" in heard[0]


def test_progress_lines_keep_it_quiet():
    heard: list[str] = []
    with Watchdog(0.3, on_expire=heard.append, poll_s=0.02) as dog:
        for _ in range(12):  # 0.6 s in all, never 0.3 s without a beat
            time.sleep(0.05)
            dog.beat()
    assert not dog.expired and heard == []


def test_zero_disables_it():
    heard: list[str] = []
    with Watchdog(0.0, on_expire=heard.append, poll_s=0.01) as dog:
        time.sleep(0.05)
    assert not dog.expired and heard == []
