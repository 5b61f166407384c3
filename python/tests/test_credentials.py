"""A client with wrong credentials, or refused by the robot's access rules, is
told the robot may have refused them (issue 17), against a real `situate run`
whose robot file turns on user-password authentication and Zenoh's ACL."""

from __future__ import annotations

import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from support import REPO, STARTUP_S, free_port, program_env, run, situate_program

import situate
from situate import _link
from situate.errors import SituateError

ROBOT = """\
robot: credbot
cycle: {{rate_hz: 50}}
devices:
  - name: sonar
    type: toy.sonar
  - name: wheels
    type: toy.wheels
skills:
  - name: runaway
    type: toy.runaway
  - name: wander
    type: toy.wander
    active: false
link:
  zenoh:
    transport:
      auth:
        usrpwd: {{dictionary_file: "{users}"}}
    access_control:
      enabled: true
      default_permission: deny
      rules:
        - id: control
          permission: allow
          flows: [ingress, egress]
          messages: [query, reply, put, declare_subscriber]
          key_exprs: ["situate/credbot/**", "situate/*/req/hello"]
        - id: read_only
          permission: allow
          flows: [ingress, egress]
          messages: [query, reply]
          key_exprs: ["situate/*/req/hello", "situate/credbot/req/stats"]
      subjects:
        - {{id: sequencers, usernames: [sequencer]}}
        - {{id: viewers, usernames: [viewer]}}
      policies:
        - {{rules: [control], subjects: [sequencers]}}
        - {{rules: [read_only], subjects: [viewers]}}
"""


def usrpwd(user: str, password: str) -> dict[str, Any]:
    return {"transport": {"auth": {"usrpwd": {"user": user, "password": password}}}}


SEQUENCER = usrpwd("sequencer", "seq-secret")


@pytest.fixture
def credbot(tmp_path: Path) -> Iterator[str]:
    """`situate run` of a robot with users and access rules; its endpoint."""
    users = tmp_path / "users.txt"
    users.write_text("sequencer:seq-secret\nviewer:view-secret\n")
    robot_file = tmp_path / "credbot.yaml"
    robot_file.write_text(ROBOT.format(users=users))
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    process = subprocess.Popen(
        [situate_program(), "run", str(robot_file), "--listen", endpoint],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=program_env(),
        cwd=REPO,
    )
    try:
        # Up when the sequencer's credentials get an answer (bounded).
        deadline = time.monotonic() + STARTUP_S
        while True:
            if process.poll() is not None:
                err = process.communicate()[1]
                pytest.fail(f"`situate run` exited with {process.returncode}:\n{err}")
            try:
                session = _link.open_session([endpoint], extra=SEQUENCER)
            except SituateError:
                session = None
            if session is not None:
                try:
                    _link.hello(session, "credbot", timeout=2.0, endpoints=[endpoint])
                    break
                except SituateError:
                    pass
                finally:
                    _link.close_session(session)
            if time.monotonic() > deadline:
                pytest.fail(f"the manager did not answer the sequencer within {STARTUP_S} s")
            time.sleep(0.05)
        yield endpoint
    finally:
        process.terminate()
        try:
            process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=20)
        process.communicate()


def test_a_client_with_the_right_credentials_is_answered(credbot: str) -> None:
    async def main() -> None:
        async with situate.connect("credbot", endpoint=credbot, zenoh_config=SEQUENCER) as robot:
            assert robot.hello.robot == "credbot"

    run(main())


@pytest.mark.parametrize(
    "credentials",
    [usrpwd("sequencer", "guess"), usrpwd("intruder", "seq-secret"), {}],
    ids=["a wrong password", "an unknown user", "no credentials"],
)
def test_a_client_with_wrong_credentials_is_told_the_robot_may_have_refused_them(
    credbot: str, credentials: dict[str, Any]
) -> None:
    # It was told only "no skill manager answered … is `situate run` running?".
    async def main() -> None:
        connecting = situate.connect(
            "credbot", endpoint=credbot, timeout=2.0, zenoh_config=credentials
        )
        async with connecting:
            pytest.fail("connected with wrong credentials")

    with pytest.raises(situate.NotRunning, match="credentials"):
        run(main())


def test_a_request_the_access_rules_refuse_says_they_may_have(credbot: str) -> None:
    async def main() -> None:
        viewer = usrpwd("viewer", "view-secret")
        connecting = situate.connect("credbot", endpoint=credbot, timeout=2.0, zenoh_config=viewer)
        async with connecting as robot:
            await robot.stats()  # allowed
            with pytest.raises(situate.NotRunning, match="credentials or access rules"):
                await robot.activate("wander")

    run(main())
