"""Case-based reasoning over qualitative posture features.

One module per phase of the 4R cycle, so the cycle can be read from the file names:

- :mod:`cbr.problem`: the feature configuration and ``extract_problem`` (clip -> problem);
- :mod:`cbr.casebase`: the in-memory case base (arrays + the measure's search index);
- :mod:`cbr.similarity`: similarity measures as plug-ins (``euclidean``, ``dtw``,
  ``signature``; register your own by name);
- :mod:`cbr.retrieve`, :mod:`cbr.reuse`, :mod:`cbr.revise`, :mod:`cbr.retain`: the cycle;
- :mod:`cbr.maintenance`: novelty/benefit trimming and the CNN, RENN, ICF editors;
- :mod:`cbr.explain`: explanations in words;
- :mod:`cbr.weights`, :mod:`cbr.fitting`: learned feature weights and side handling;
- :mod:`cbr.novelty`: how unlike the stored cases a clip is, calibrated per case base;
- :mod:`cbr.estimator`: ``CaseBaseClassifier`` (scikit-learn contract; ``solve`` is the one
  classification path);
- :mod:`cbr.stored`: a fitted classifier stored with its case base and loaded back whole;
- :mod:`cbr.training`, :mod:`cbr.classification`: ``posecbr train`` (fit, then store) and
  ``posecbr classify`` (load, solve, explain, feedback); the store is :mod:`casebase_store`.

Beside the core, in their own subpackages (the core imports neither):

- :mod:`cbr.dad`: the DAD expert-system baseline;
- :mod:`cbr.evaluation`: the comparison harness, its statistics, pictures and HTML report.
"""
