# Type stub: at run time toolkit.bending is toolkit.papers.bending itself (a short name
# registered by toolkit/__init__.py); this stub gives type checkers the same names.
from .papers.bending import *  # noqa: F403
