"""A meshcat server bound to 127.0.0.1 only (``python -m toolkit.viz.server``).

meshcat's own ``meshcat-server`` announces a 127.0.0.1 URL but lets tornado listen on
every interface; this entry point forces the web server's listening address to the
loopback interface (the ZeroMQ socket already binds to the host it is given).

``--parent PID``: the server watches that process and exits within about half a second
once it is gone, whatever ended it (SIGKILL, a crash, Ctrl-C), so no server outlives the
Python process that started it.
"""

from __future__ import annotations

import os
import sys
import threading
import time


def _watch(parent: int) -> None:
    """Exit this process once ``parent`` has ended (polled twice a second)."""
    while True:
        time.sleep(0.5)
        if os.getppid() != parent:
            os._exit(0)
        try:
            os.kill(parent, 0)
        except ProcessLookupError:
            os._exit(0)
        except PermissionError:
            pass


def main(argv: list[str] | None = None) -> None:
    args = sys.argv[1:] if argv is None else argv
    if len(args) == 2 and args[0] == "--parent":
        threading.Thread(target=_watch, args=(int(args[1]),), daemon=True).start()
    import tornado.web
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    listen = tornado.web.Application.listen

    def loopback_listen(self, port, address="", **kwargs):
        return listen(self, port, address="127.0.0.1", **kwargs)

    tornado.web.Application.listen = loopback_listen  # type: ignore[method-assign]
    bridge = ZMQWebSocketBridge(host="127.0.0.1")
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    try:
        bridge.run()
    except KeyboardInterrupt:
        sys.exit(0)


if __name__ == "__main__":
    main()
