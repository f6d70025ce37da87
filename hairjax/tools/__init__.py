"""hairjax.tools: the benchmark, the settings search (the one-knob sweep and the joint
search, one engine) and its report, and the compare report.

Built on the library (`import hairjax`), which never imports them: `hairjax bench`,
`hairjax sweep` and `hairjax compare` import them when they run, and so do experiments/
and notebooks/.
"""

from ._bench import bench_main as bench_main
from ._bench_cases import GL_PASSES as GL_PASSES
from ._bench_cases import STAGES as STAGES
from ._bench_cases import TARGETS as TARGETS
from ._bench_cases import bench_scene as bench_scene
from ._bench_cases import configurations as configurations
from ._compare import TimedCalls as TimedCalls
from ._compare import compare as compare
from ._compare import format_report as format_report
from ._compare import image_stats as image_stats
from ._compare import median_time as median_time
from ._compare import timed_calls as timed_calls
from ._knob_space import KnobSpace as KnobSpace
from ._knob_space import OneKnobSpace as OneKnobSpace
from ._knob_space import knob_space as knob_space
from ._knob_space import one_knob_space as one_knob_space
from ._knobs import JOINT_KNOBS as JOINT_KNOBS
from ._knobs import KNOBS as KNOBS
from ._knobs import QUICK_JOINT_KNOBS as QUICK_JOINT_KNOBS
from ._knobs import QUICK_KNOBS as QUICK_KNOBS
from ._knobs import SweepError as SweepError
from ._knobs import knob_scene as knob_scene
from ._knobs import settings_scene as settings_scene
from ._pareto import SearchConfig as SearchConfig
from ._pareto import pareto_front as pareto_front
from ._pareto import pareto_search as pareto_search
from ._plot import THRESHOLDS as THRESHOLDS
from ._plot import pareto_plot as pareto_plot
from ._report import cheapest as cheapest
from ._report import summary_markdown as summary_markdown
from ._report import write_report as write_report
from ._search import PATHS as PATHS
from ._search import run_joint as run_joint
from ._search import run_search as run_search
from ._search import run_sweep as run_sweep
from ._store import load_joint as load_joint
from ._store import load_points as load_points
