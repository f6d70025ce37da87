"""hairjax.tools: the benchmark, the sweep, the joint search and their reports, and the
compare report.

Built on the library (`import hairjax`), which never imports them: `hairjax bench`,
`hairjax sweep` and `hairjax compare` import them when they run, and so do experiments/
and notebooks/.
"""

from .._io._files import atomic_path as atomic_path
from .._io._files import write_csv as write_csv
from .._io._files import write_json as write_json
from .._io._files import write_text as write_text
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
from ._joint import load_joint as load_joint
from ._joint import run_joint as run_joint
from ._joint_report import JOINT_THRESHOLDS as JOINT_THRESHOLDS
from ._joint_report import joint_markdown as joint_markdown
from ._joint_report import joint_plot as joint_plot
from ._joint_report import write_joint_report as write_joint_report
from ._knob_space import KnobSpace as KnobSpace
from ._knob_space import knob_space as knob_space
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
from ._sweep import PATHS as PATHS
from ._sweep import load_points as load_points
from ._sweep import run_sweep as run_sweep
from ._sweep_report import THRESHOLDS as THRESHOLDS
from ._sweep_report import cheapest as cheapest
from ._sweep_report import pareto_plot as pareto_plot
from ._sweep_report import summary_markdown as summary_markdown
from ._sweep_report import write_report as write_report
