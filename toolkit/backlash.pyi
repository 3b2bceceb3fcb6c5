# Type stub: at run time toolkit.backlash is toolkit.papers.backlash itself (a short name
# registered by toolkit/__init__.py); this stub gives type checkers the same names.
from .papers.backlash import *  # noqa: F403
