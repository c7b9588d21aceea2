"""nbgrader's Execute preprocessor, made to refuse a kernel that cannot import the reference.

Without ``solutions`` on the kernel's path every hidden test fails with ModuleNotFoundError and
nbgrader still reports success, so a misconfigured grader would give a whole class zero.
``nbgrader_config.py`` puts this preprocessor in place of Execute, so plain ``nbgrader autograde``
refuses too.
"""

from __future__ import annotations

from jupyter_core.utils import ensure_async, run_sync
from nbgrader.preprocessors import Execute

PROBE = "__import__('solutions')"


class ReferenceUnavailable(RuntimeError):
    """The grading kernel cannot import the hidden ``solutions`` package."""


class ExecuteWithReference(Execute):
    """Execute, after checking that the kernel can import ``solutions``."""

    async def async_start_new_kernel_client(self):
        kc = await super().async_start_new_kernel_client()
        msg_id = await ensure_async(kc.execute(PROBE, silent=True, store_history=False))
        reply = await self.async_wait_for_reply(msg_id)
        if reply is None or reply["content"]["status"] != "ok":
            content = reply["content"] if reply else {}
            await self._async_cleanup_kernel()
            raise ReferenceUnavailable(
                "The grading kernel cannot import the hidden reference package `solutions` "
                f"({content.get('ename', 'no reply')}: {content.get('evalue', '')}). Every hidden test "
                "would fail, so nothing was graded. Run nbgrader from the course root, whose "
                "nbgrader_config.py puts the root on the kernel's PYTHONPATH."
            )
        return kc

    # nbclient binds the synchronous twin to the base class's coroutine; bind it to ours.
    start_new_kernel_client = run_sync(async_start_new_kernel_client)
