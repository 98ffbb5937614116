"""Servers for tests, run as `python -m tests.support.openpi_servers MODE PORT [POLICY [KEY=VALUE ...]]`.

Modes:
  openpi-langgap  openpi's own `WebsocketPolicyServer` (PyPI `openpi-server`) hosting a LangGap policy
                  through `ServedPolicy`, i.e. announcing LangGap's extension in its metadata.
  langgap-record  `openpi-langgap`, also saving every request as it arrived, decoded, to
                  RECORD_DIR/requests.jsonl (arrays as lists: for policies without cameras): the wire.
  openpi-record   openpi's server with plain metadata: a stand-in for an openpi model server that saves
                  every observation it receives to RECORD_DIR/<n>.npz and answers a (10, 7) chunk: no-ops
                  (gripper open), or with REPLY_ACTIONS (an .npy of (N, 7) actions) the next 10 of them,
                  advancing 5 (openpi's replan_steps) per request.
  garbage         a websocket server that answers every request with bytes that are not msgpack.
  bad-actions     a websocket server that answers `{"actions": "not an array"}`.
"""

from __future__ import annotations

import os
import pathlib
import sys

import numpy as np


class RecordingOpenpiModel:
    """openpi's server-side policy interface: `infer(obs) -> {"actions": ...}`."""

    def __init__(self, directory: pathlib.Path, replies: np.ndarray | None = None):
        self.directory = directory
        self.replies = replies
        self.calls = 0

    def infer(self, obs: dict) -> dict:
        np.savez(self.directory / f"{self.calls:04d}.npz", **{k: np.asarray(v) for k, v in obs.items()})
        actions = np.zeros((10, 7))
        actions[:, 6] = -1.0
        if self.replies is not None:
            chunk = self.replies[5 * self.calls : 5 * self.calls + 10]
            actions[: len(chunk)] = chunk
        self.calls += 1
        return {"actions": actions}

    def reset(self) -> None:
        pass


def _recording(served):
    """`served` with every request written to RECORD_DIR first, before `ServedPolicy` removes anything."""
    import json

    from langgap.policies import protocol

    infer = served.infer
    path = pathlib.Path(os.environ["RECORD_DIR"]) / "requests.jsonl"

    def recorded(request: dict) -> dict:
        with path.open("a") as handle:
            handle.write(json.dumps(protocol.jsonable(request)) + "\n")
        return infer(request)

    served.infer = recorded
    return served


def _serve_raw(port: int, reply: bytes) -> None:
    from websockets.sync.server import serve

    from langgap.policies import protocol
    from langgap.serve import health_check

    def handle(connection):
        connection.send(protocol.pack({}))
        for _ in connection:
            connection.send(reply)

    with serve(handle, "127.0.0.1", port, process_request=health_check, max_size=None) as server:
        server.serve_forever()


def main(mode: str, port: int, *rest: str) -> None:
    from langgap.policies import protocol

    if mode in ("openpi-langgap", "langgap-record", "openpi-record"):
        from openpi_server import WebsocketPolicyServer

        if mode != "openpi-record":
            from langgap.policies import make_policy
            from langgap.serve import ServedPolicy

            name, pairs = rest[0], rest[1:]
            served = ServedPolicy(make_policy(name, dict(p.split("=", 1) for p in pairs)), name)
            policy, metadata = _recording(served) if mode == "langgap-record" else served, served.metadata
        else:
            replies = np.load(os.environ["REPLY_ACTIONS"]) if "REPLY_ACTIONS" in os.environ else None
            policy = RecordingOpenpiModel(pathlib.Path(os.environ["RECORD_DIR"]), replies)
            metadata = {"model": "recorder"}
        WebsocketPolicyServer(policy, host="127.0.0.1", port=port, metadata=metadata).serve_forever()
    elif mode == "garbage":
        _serve_raw(port, b"\xc1\xc1 not msgpack")
    elif mode == "bad-actions":
        _serve_raw(port, protocol.pack({"actions": "not an array"}))
    else:
        raise SystemExit(f"unknown mode {mode}")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), *sys.argv[3:])
