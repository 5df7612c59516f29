"""The jupyter_client and nbclient seam: the only code that relies on their private parts.

The sandbox's kernels are forked from the zygote (:mod:`.zygote`) rather than started as new
Pythons, and each notebook runs in nbclient with the guard and the grader's tests
(:mod:`.notebook`). Both need more than the documented API; each name they rely on is listed in
:data:`PRIVATE`, with what it is used for, and :func:`check` looks for every one of them in the
installed packages before the first notebook runs. Checked with the versions in
:data:`CHECKED`.

Runs inside the sandbox: the standard library only at load time.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import signal
import sys
import time
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

from .zygote import POLL_SECONDS, Zygote

__all__ = ["CHECKED", "PRIVATE", "SeamError", "check", "forking_manager_class", "missing"]

#: The versions of the packages whose private parts :data:`PRIVATE` lists, read and tested.
CHECKED: Dict[str, Tuple[str, ...]] = {"jupyter_client": ("8.10.0",), "nbclient": ("0.11.0",)}

#: ``(module, class, name, use, what for)``: each name beyond the documented API used here.
#: ``use`` is how: ``overrides``, ``calls`` or ``reads`` (the name must be there), or ``sets``
#: (set as the usual launch sets it: where a version lacks the name, it does not read it, and
#: setting it changes nothing). The names of nbclient's client are attributes of an instance,
#: the others of the class.
PRIVATE: Tuple[Tuple[str, str, str, str, str], ...] = (
    ("jupyter_client.manager", "AsyncKernelManager", "_async_pre_start_kernel", "overrides",
     "gives the manager the provisioner that forks the kernel"),
    ("jupyter_client.manager", "AsyncKernelManager", "_async_wait", "overrides",
     "looks every 5 ms whether a killed kernel has ended, not every 100"),
    ("jupyter_client.manager", "AsyncKernelManager", "provisioner", "reads",
     "set before the start when none is, so the manager keeps the forking provisioner"),
    ("jupyter_client.asynchronous", "AsyncKernelClient", "_handle_kernel_info_reply", "calls",
     "the shorter wait for a new kernel (PromptClient.wait_for_ready)"),
    ("jupyter_client.asynchronous", "AsyncKernelClient", "_async_is_alive", "calls",
     "the shorter wait for a new kernel"),
    ("jupyter_client.provisioning", "LocalProvisioner", "connection_info", "reads",
     "returned by the forking launch, as the usual launch returns it"),
    ("jupyter_client.provisioning", "LocalProvisioner", "pid", "sets",
     "the forked kernel's process id"),
    ("jupyter_client.provisioning", "LocalProvisioner", "pgid", "sets",
     "the forked kernel's process group"),
    ("jupyter_client.provisioning", "LocalProvisioner", "cwd", "sets",
     "the forked kernel's working folder (8.10 resolves the connection file against it)"),
    ("nbclient", "NotebookClient", "nb", "reads",
     "the notebook; a hidden cell's run puts the notebook's own cell back in it"),
    ("nbclient", "NotebookClient", "km", "reads",
     "the kernel manager, whose provisioner names the kernel"),
    ("nbclient", "NotebookClient", "code_cells_executed", "reads",
     "counted up for a test cell the grader runs on its side"),
)  # fmt: skip


class SeamError(RuntimeError):
    """The installed jupyter_client or nbclient lacks a private part the sandbox relies on."""


def missing(private: Optional[Sequence[Tuple[str, str, str, str, str]]] = None) -> List[str]:
    """What the installed packages lack of ``private`` (:data:`PRIVATE`): ``module.Class.name``.

    A name the sandbox only ``sets`` is not looked for (see :data:`PRIVATE`); its class is.
    """
    lacking = []
    for module_name, class_name, name, use, _ in PRIVATE if private is None else private:
        try:
            owner: Any = getattr(importlib.import_module(module_name), class_name)
        except (ImportError, AttributeError):
            lacking.append(f"{module_name}.{class_name}")
            continue
        if module_name == "nbclient":
            import nbformat

            owner = owner(nbformat.v4.new_notebook())
        if use != "sets" and not hasattr(owner, name):
            lacking.append(f"{module_name}.{class_name}.{name}")
    return list(dict.fromkeys(lacking))


def check() -> None:
    """Raise :class:`SeamError` naming every private part the installed packages lack."""
    lacking = missing()
    if lacking:
        checked = "; ".join(
            f"{package} {', '.join(versions)}" for package, versions in CHECKED.items()
        )
        pins = " ".join(f"{package}=={versions[-1]}" for package, versions in CHECKED.items())
        raise SeamError(
            f"the installed Jupyter packages lack {', '.join(lacking)}, which the grader's "
            f"sandbox relies on (checked with {checked}); install {pins}."
        )


def forking_manager_class(zygote: Zygote) -> type:
    """An AsyncKernelManager whose kernels the zygote forks, when it can.

    Its provisioner is jupyter_client's ``LocalProvisioner`` (connection file, ports, the
    usual launch as the fallback) with the launch and the process handling of a forked kernel:
    poll and wait read the exit status the zygote reports, signals go to the kernel's process
    group (an interrupt is SIGINT, as for a kernel launched the usual way).
    """
    import uuid

    from jupyter_client.manager import AsyncKernelManager

    provisioner = _forked_provisioner_class(zygote)

    class ForkingKernelManager(AsyncKernelManager):
        client_factory = _prompt_client_class()

        async def _async_wait(self, pollinterval: float = 0.1) -> None:
            # A killed kernel is gone in milliseconds: look every 5 ms, not every 100.
            await super()._async_wait(pollinterval=min(pollinterval, POLL_SECONDS))

        async def _async_pre_start_kernel(self, **kw: Any) -> Any:
            if self.provisioner is None:
                self.kernel_id = self.kernel_id or kw.pop("kernel_id", str(uuid.uuid4()))
                self.provisioner = provisioner(
                    kernel_id=self.kernel_id, kernel_spec=self.kernel_spec, parent=self
                )
            return await super()._async_pre_start_kernel(**kw)

    return ForkingKernelManager


def _forked_provisioner_class(zygote: Zygote) -> type:
    """jupyter_client's ``LocalProvisioner``, launching through ``zygote`` when it can."""
    import asyncio

    from jupyter_client.provisioning import LocalProvisioner

    class ForkedProvisioner(LocalProvisioner):
        forked: Optional[int] = None

        @property
        def has_process(self) -> bool:
            return self.forked is not None or super().has_process

        async def launch_kernel(self, cmd: List[str], **kwargs: Any) -> Any:
            usual = set(kwargs) <= {"env", "cwd", "kernel_id"}  # nothing only Popen can do
            if usual and is_ipykernel(cmd):
                pid = zygote.launch(cmd, kwargs.get("cwd"), kwargs.get("env", dict(os.environ)))
                if pid is not None:
                    self.forked = self.pid = self.pgid = pid
                    self.cwd = kwargs.get("cwd") or Path.cwd()
                    return self.connection_info
            return await super().launch_kernel(cmd, **kwargs)

        async def poll(self) -> Optional[int]:
            if self.forked is None:
                return await super().poll()
            return zygote.exit_code(self.forked)

        async def wait(self) -> Optional[int]:
            if self.forked is None:
                return await super().wait()
            while zygote.exit_code(self.forked) is None:
                await asyncio.sleep(POLL_SECONDS)
            code = zygote.exit_code(self.forked)
            self.forked = None
            return code

        async def send_signal(self, signum: int) -> None:
            if self.forked is None:
                await super().send_signal(signum)
            elif zygote.exit_code(self.forked) is None:
                try:
                    os.killpg(self.forked, signum)
                except OSError:
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(self.forked, signum)

        async def kill(self, restart: bool = False) -> None:
            if self.forked is None:
                await super().kill(restart)
            else:
                await self.send_signal(signal.SIGKILL)

        async def terminate(self, restart: bool = False) -> None:
            if self.forked is None:
                await super().terminate(restart)
            else:
                await self.send_signal(signal.SIGTERM)

    return ForkedProvisioner


def _prompt_client_class() -> type:
    """jupyter_client's ``AsyncKernelClient``, with a shorter wait for a new kernel."""
    from queue import Empty

    from jupyter_client.asynchronous import AsyncKernelClient

    class PromptClient(AsyncKernelClient):
        """jupyter_client's client, with the wait for a new kernel cut to what it needs.

        Once the kernel has answered ``kernel_info`` and its first IOPub message arrived, the
        usual wait still listens 0.2 s for more IOPub messages before it returns: a fifth of a
        second per notebook, idle. Here it stops after 20 ms of silence; later messages of the
        start are told apart by their parent anyway, as nbclient reads only its own.
        """

        async def wait_for_ready(self, timeout: Optional[float] = None) -> None:
            deadline = time.monotonic() + (60.0 if timeout is None else timeout)
            while True:
                self.kernel_info()
                try:
                    reply = await self.shell_channel.get_msg(timeout=0.5)
                except Empty:
                    reply = None
                if reply is not None and reply["msg_type"] == "kernel_info_reply":
                    try:
                        await self.iopub_channel.get_msg(timeout=0.2)
                    except Empty:
                        pass
                    else:
                        self._handle_kernel_info_reply(reply)
                        break
                if not await self._async_is_alive():
                    raise RuntimeError("Kernel died before replying to kernel_info")
                if time.monotonic() > deadline:
                    raise RuntimeError(f"Kernel didn't respond in {timeout} seconds")
            while True:
                try:
                    await self.iopub_channel.get_msg(timeout=0.02)
                except Empty:
                    break

    return PromptClient


def is_ipykernel(command: Sequence[str]) -> bool:
    """Whether ``command`` runs ipykernel with this Python, as the zygote would."""
    return (
        len(command) >= 3
        and list(command[1:3]) == ["-m", "ipykernel_launcher"]
        and Path(command[0]).absolute() == Path(sys.executable).absolute()
    )
