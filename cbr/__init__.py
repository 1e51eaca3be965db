"""Case-based reasoning over qualitative posture features.

One module per phase of the 4R cycle, so the cycle can be read from the file names:

- :mod:`cbr.problem`: the feature configuration and ``extract_problem`` (clip -> problem);
- :mod:`cbr.casebase`: the in-memory case base (arrays + the measure's search index);
- :mod:`cbr.similarity`: similarity measures as plug-ins (``euclidean``, ``dtw``,
  ``signature``; register your own by name);
- :mod:`cbr.retrieve`, :mod:`cbr.reuse`, :mod:`cbr.revise`, :mod:`cbr.retain`: the cycle;
- :mod:`cbr.maintenance`: novelty/benefit trimming and the CNN, RENN, ICF editors;
- :mod:`cbr.explain`: explanations in words;
- :mod:`cbr.estimator`: ``CaseBaseClassifier`` (scikit-learn contract);
- :mod:`cbr.build`: building and classifying with a stored case base (``posecbr train`` /
  ``classify``); the store itself is :mod:`casebase_store`.

Beside the core, in their own subpackages (the core imports neither):

- :mod:`cbr.dad`: the DAD expert-system baseline;
- :mod:`cbr.evaluation`: the comparison harness, its statistics, pictures and HTML report.
"""
