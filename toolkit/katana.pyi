# Type stub: at run time toolkit.katana is toolkit.papers.katana itself (a short name
# registered by toolkit/__init__.py); this stub gives type checkers the same names.
from .papers.katana import *  # noqa: F403
