"""A meshcat server bound to 127.0.0.1 only (``python -m toolkit._meshcat_server``).

meshcat's own ``meshcat-server`` announces a 127.0.0.1 URL but lets tornado listen on
every interface; this entry point forces the web server's listening address to the
loopback interface (the ZeroMQ socket already binds to the host it is given).
"""

from __future__ import annotations

import sys


def main() -> None:
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
