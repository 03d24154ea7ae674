"""The benchmark's suite: instances where optimisers differ, runs through the harness, and the
measures COCO and IOHprofiler define (targets relative to f*, runtime ECDFs, ERT).

``spec`` (what a suite holds: ``conf/suite_*.yaml``), ``instances`` (data sets written once),
``fstar`` (the best-known cost and how it was found), ``jobs`` (Hydra sweeps through the
project's launchers), ``measures``, ``figures``, ``report`` (tables and the IOHprofiler export),
``user`` (the measures on a user's own folders), ``cost`` (the measured cost of a suite), ``cli``.
"""
