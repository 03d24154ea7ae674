"""GENESIS 5.0 (Grefenstette 1990), a clean-room clone, as an optimiser plugin.

The clone reproduces the trajectory of the original program bit for bit (same ``out`` lines,
same ``min`` list) for the same settings, template, seed and objective. It is checked against the
original's own worked example (``f = x1^2 + x2^2 + x3^2``), kept with its settings, template and
the ``out`` and ``min`` files the original wrote in ``tests/plugins/genesis_vectors/ex1/`` (``ex1``
below) and reproduced byte for byte by ``tests/plugins/test_genesis.py``.

Two ways to use it
------------------
* As the benchmark's optimiser plugin: :func:`minimize` (Hydra config ``conf/optimizer/genesis.yaml``).
  Genes span ``[problem.lower, problem.upper]`` with ``2**bits_per_gene`` values each, Total Trials
  is the harness's budget and the objective is the problem cost (always minimised).
* As a stand-in for the original program::

      python -m plugins.genesis DIR                    # objective: x1^2 + x2^2 + ... (sum of squares)
      python -m plugins.genesis DIR module:function    # objective: module.function(x) -> float
      python -m plugins.genesis DIR --out-dir OUTDIR   # write out/min to OUTDIR instead of DIR

  reads ``DIR/in`` and ``DIR/template`` in the original formats and writes ``out`` and ``min``
  into ``DIR`` as the original does (into ``OUTDIR``, created if missing, with ``--out-dir``),
  then prints one summary line. ``plugins/genesis_example/`` is a small ready-made ``DIR``.
  ``module:function`` is imported with ``importlib`` (the current directory is on the path); the
  function receives the decoded genes as a 1-D float64 numpy vector and returns a float. Bad
  input (missing file, malformed line, bad value, unimportable objective) prints one line naming
  the file and line and exits with status 2.

The original's files
--------------------
``in``: 16 lines ``Label = value``, in this order (the original's defaults in brackets; the
labels are matched ignoring case and repeated blanks, blank lines are skipped)::

           Experiments = 1          [1]
          Total Trials = 1000       [1000]    stop once this many evaluations were made
       Population Size = 50         [50]      N
      Structure Length = 30         [30]      L, bits per structure (= the template's bits)
        Crossover Rate = 0.6        [0.6]
         Mutation Rate = 0.001      [0.001]   per bit; a mutated bit is redrawn, so it flips half the time
        Generation Gap = 1.0        [1.0]     share of the population replaced each generation
        Scaling Window = 5          [5]       generations over which the worst cost is remembered
       Report Interval = 200        [100]     trials between two ``out`` lines
      Structures Saved = 5          [10]      length of the ``min`` list
     Max Gens w/o Eval = 2          [2]       stop after this many generations without a trial
         Dump Interval = 0          [0]       (checkpoints: ignored by the clone)
           Dumps Saved = 0          [0]       (ignored)
               Options = acefgL     [cefgl]   option letters, see below
           Random Seed = 123456789  [123456789]
              Rank Min = 0.75       [0.75]    expected count of the worst structure with ``R``

Options: ``a`` evaluate every structure each generation (unchanged copies cost a trial too);
``c`` collect statistics and convergence measures (``out`` lines with Lost/Conv/Bias, and the
``Bias > 0.99`` stop); ``C`` statistics only; ``e`` elitist; ``f`` floating-point genes from the
``template``; ``g`` Gray code (with ``f``); ``M`` maximise (default: minimise); ``R`` rank
selection (default: proportional). ``l``, ``L``, ``d``, ``o``, ``O``, ``b``, ``D``, ``I``, ``s``,
``t`` and unknown letters are accepted and ignored; ``i`` and ``r`` are refused (see below).

``template`` (read with option ``f``): ``genes: n``, then for each gene a ``gene k`` line and the
lines ``min: x``, ``max: x``, ``values: v`` (a power of two) and ``format: %7.2f`` (the printf
format of the gene in the ``min`` file); blank lines are ignored. A gene takes ``log2(values)``
consecutive bits, most significant first (Gray-decoded first with ``g``), and the integer ``k``
they encode gives ``min + k * (max - min) / (values - 1)``. Example::

    genes: 1

    gene 0
    min: -5.12
    max: 5.11
    values: 1024
    format: %7.2f

``out`` (written with ``c`` or ``C``): one line per report point, in the C format
``"%5d %5d %2d %2d %5.3f %.6e %.6e %.6e %.6e"``: generation, trials, Lost (bit positions where
all N structures agree), Conv (positions where at most ``N // 20`` disagree), Bias (mean share
of the majority allele), online (mean of all costs so far), offline (mean of the best-so-far
after each trial), best cost so far, population average. Report points are generation 0 and
each generation whose trials reach the next multiple of Report Interval. A run declared
converged (``c`` and ``Bias > 0.99``) stops, and the original pads ``out`` with copies of the last
line whose generation number advances by ``Report Interval // N`` per line, one line per Report
Interval still missing before Total Trials (converged at generation 169 with 17000 of 20000
trials at N = 100, Report Interval 1000: lines for 169, 179, 189, 199, all with 17000 trials).

``min``: the best distinct structures found (Structures Saved of them, in slot order), one per
line: each gene in its template format (without ``f``: the string of 0s and 1s), then the cost
as ``"  %11.4e "``, then ``" %4d  %4d"`` the generation and trial at which it was first found.

Random seed of the plugin
-------------------------
``random_seed`` (the RANDU seed) if given, else derived from the harness's integer ``seed``:
``seed == 0`` gives the paper's 123456789; any other seed ``s`` gives
``(splitmix64(s mod 2**64) >> 33) | 1``, a 31-bit odd number, so never 0 (RANDU would stick at 0)
and neighbouring seeds give unrelated RANDU streams.

Non-finite costs
----------------
A cost of ``+inf`` or NaN (a diverging candidate) is replaced by :data:`INF_COST` ``= 1e300``
(``-1e300`` when maximising), ``-inf`` by ``-1e300`` (``+1e300`` when maximising), so the
proportional-selection arithmetic stays finite (``1e300 * 1.0001`` and population sums of up to
~1e8 such values do not overflow). While such a value is the scaling window's ``Worst`` the finite
candidates all get (nearly) the same expected count: that is what the original does with a huge
cost too.

Readings chosen where the description leaves room (the ones ex1 decides are marked [ex1])
----------------------------------------------------------------------------------------
* RANDU: ``seed = seed * 65539 mod 2**31``, advanced first, then scaled:
  ``Rand() = new_seed * 0.4656612875e-9``; ``Randint(lo, hi) = int(lo + (hi - lo + 1) * Rand())``
  [ex1; from 123456789 the first three ``Rand()`` are 0.7746705113383283, 0.13062164053126013,
  0.8116952440327436].
* Gene values: ``min + integer * step`` with ``step = (max - min) / (values - 1)`` in double
  precision, as the original describes it (ex1 does not tell it from ``min + (max - min) * i / (values - 1)``);
  the runner's sum of squares is accumulated left to right from 0.0 like a C loop.
* Mutation positions are 0-based indices into the population's bit array, so the first gap
  (>= 1) never hits bit 0 of structure 0 [ex1].
* Crossover: parents that agree outside ``[x1, x2)`` are left alone; otherwise the segment is
  exchanged and both children are marked if the segments differed [ex1: always exchanging does
  not reproduce it; with ``a`` the marking itself is moot].
* Evaluation: the offline sum adds the best-so-far *after* it is updated with the trial [ex1].
* Saved list (``min``): a string already in the list is skipped; while the list is not full the
  string takes the next free slot; when full it replaces the worst saved entry if strictly
  better [ex1: slot order, not sorted]. Which slot goes on a tie of worst entries (the first
  here) and whether an equal cost replaces (no here) ex1 does not decide.
* Crossover points: ``x1 = Randint(0, L)``, ``x2 = Randint(0, L - 1)`` as the original describes
  [ex1: ``Randint(0, L - 1)``, ``Randint(0, L - 2)`` does not reproduce it].
* Elitist: the copy is made only when no new string equals the old best [ex1: always copying
  does not reproduce it].
* ``out`` best column: the best value ever found (with ``e`` it is also the population's best).
* Report points: generation 0, and every generation whose trial count reaches the next multiple
  of Report Interval above the trials of the previous report (one line even if several multiples
  were passed). No extra line is written at termination unless it is such a point.
* ``Lost``/``Conv``/``Bias`` are computed at report points with option ``c`` only; so the
  ``Lost = L`` stop and the ``Bias > 0.99`` stop are checked there. On ``Bias > 0.99`` the report
  line is written, then the padding lines (see "The original's files" above: same trials and
  statistics, generation advanced by ``Report Interval // N``, at least 1, per line), and the run
  stops. The step is the original's ``Report Interval / Population Size`` in integer arithmetic,
  whatever the Generation Gap (with ``a`` a generation costs N trials at any gap); the number of
  lines is ``ceil((Total Trials - trials) / Report Interval)``. ``RunResult.generations`` counts
  the generations really evaluated, not the padded ones. (ex1 does not converge; the padding is
  checked against the original's documented example, 169, 179, 189, 199.)
* ``C`` without ``c``: ``out`` lines are written with Lost, Conv, Bias = 0, 0, 0.000. Neither
  ``c`` nor ``C``: no ``out`` file is written.
* Rank selection (``R``): the population is sorted best first with a stable sort, so on ties the
  earlier index gets the higher rank.
* ``Max Gens w/o Eval``: a counter of consecutive generations with no trial; the run stops when
  it reaches the setting.
* Scaling Window 0: ``Worst`` is generation 0's ``New_worst``, then replaced by a later
  ``New_worst`` only when that one is worse.
* Mutation Rate 0: the first-gap draw is still made and no bit is ever mutated (the original's
  formula divides by log(1) = 0 there).
* Select must take exactly N structures; the original's description does not say what happens otherwise (only
  possible through rounding of the expected counts). The clone stops taking at N and, if short,
  fills the rest with the last structure, so a long benchmark run is not lost.
* Experiments > 1: the experiments run one after the other on the same RANDU stream; ``out``
  receives the lines of all of them, ``min`` holds the saved list of the last one.
* Options ``i`` (initial structures from a file) and ``r`` (restart from a checkpoint) are refused;
  ``d``, ``L``, ``l``, ``o``, ``O``, ``b``, ``D``, ``I``, ``s``, ``t`` and unknown letters are
  accepted and ignored (no checkpoint, log or trace files are written). Without ``f`` the
  structures are plain bit strings: the objective receives the 0/1 bits as a float vector and the
  ``min`` file prints the string of 0s and 1s in place of the genes.
"""

from plugins.genesis.engine import Genesis, RunResult, SavedEntry, sum_of_squares
from plugins.genesis.files import format_min_lines, format_out_line, read_settings, read_template, write_min, write_out
from plugins.genesis.plugin import minimize
from plugins.genesis.randu import Randu, seed_to_randu
from plugins.genesis.runner import main, run_dir
from plugins.genesis.settings import DEFAULT_SEED, INF_COST, Gene, GenesisInputError, Settings, Template, gray_to_binary

__all__ = [
    "INF_COST",
    "DEFAULT_SEED",
    "GenesisInputError",
    "Settings",
    "Gene",
    "Template",
    "Randu",
    "Genesis",
    "RunResult",
    "SavedEntry",
    "seed_to_randu",
    "gray_to_binary",
    "read_settings",
    "read_template",
    "format_out_line",
    "format_min_lines",
    "write_out",
    "write_min",
    "sum_of_squares",
    "run_dir",
    "main",
    "minimize",
]
