"""The evaluation harness: case-base configurations, DAD and peer classifiers cross-validated on
the same folds, with statistics, tables, pictures and an HTML report (``posecbr compare`` and
``posecbr report``).

One job per module:

- :mod:`~cbr.evaluation.settings`: ``CompareSettings``, what a comparison runs;
- :mod:`~cbr.evaluation.methods`: the rows (``Method``), why one cannot run, its estimator;
- :mod:`~cbr.evaluation.peers`: the peer classifiers on limb-angle series;
- :mod:`~cbr.evaluation.data`: the clips prepared (``Prepared``: targets, subjects, groups);
- :mod:`~cbr.evaluation.folds`: leave-one-subject-out or stratified k-fold;
- :mod:`~cbr.evaluation.tasks`: one (method, fold) task, and the warming before the first;
- :mod:`~cbr.evaluation.runner`: where tasks run (in-process, or spawned worker processes);
- :mod:`~cbr.evaluation.stats`: Wilson, McNemar, macro-F1 and its bootstrap interval;
- :mod:`~cbr.evaluation.scoring`: predictions to ``Scores``, the best methods, McNemar;
- :mod:`~cbr.evaluation.segments`: a segmentation scored against labels over time
  (``posecbr segment --truth``, ``benchmarks.segment``);
- :mod:`~cbr.evaluation.results`: the typed results and their JSON (``to_dict``/``from_dict``);
- :mod:`~cbr.evaluation.compare`: ``run_compare``, the steps above in order;
- :mod:`~cbr.evaluation.misclassified`: explanations of clips got wrong (case base, DAD);
- :mod:`~cbr.evaluation.prevalence`: feature prevalence before and after trimming;
- :mod:`~cbr.evaluation.tables`: the text table and CSV rows;
- :mod:`~cbr.evaluation.pictures`: the pictures, each one allowed to fail alone;
- :mod:`~cbr.evaluation.report`: the self-contained HTML page;
- :mod:`~cbr.evaluation.machine`: machine and library versions.

It may import the CBR core and :mod:`cbr.dad`; neither imports it.
"""
