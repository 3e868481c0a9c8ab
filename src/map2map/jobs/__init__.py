"""The jobs layer: one function per command, from files in to files out.

A job takes a small typed spec, reads and checks every input and output path before
any work, runs the domain packages on arrays and dataclasses, writes its outputs
atomically and returns a typed result that lists every file it wrote (``written``,
name -> path) and keeps the in-memory domain result, so a caller can run it thousands
of times without re-reading files. The command line only parses arguments and calls
these:

==========================  ===============================  =============================
command                     job (spec -> result)             in-memory result
==========================  ===============================  =============================
plan, convert, prep, show   :mod:`map2map.jobs.maps`         the maps
deform                      :func:`map2map.jobs.deform.deform`  ``DeformResult`` per sample
simulate                    :func:`map2map.jobs.simulate.simulate`  ``SimResult``
slam                        :func:`map2map.jobs.slam.slam`   ``SlamResult``
align, evaluate             :mod:`map2map.jobs.evaluate`     ``Alignment`` / ``Evaluation``
autocorrect                 :mod:`map2map.jobs.autocorrect`  ``Correction`` per map
synthesize                  :mod:`map2map.jobs.synthesize`   ``SynthesisResult``
train ba, train ab          :mod:`map2map.jobs.train`        ``TrainResult``
dataset clean               :mod:`map2map.jobs.dataset`      the cleaner's report
==========================  ===============================  =============================

Jobs sit above the domain packages, the datasets and the learned models, so every
command goes through one.

A job that writes a folder writes it into a temporary sibling renamed whole at the end
(:func:`map2map.core._io.atomic_dir`): it exists complete or not at all, and an existing
folder is replaced. Errors name parameters (``seed``), which the command line turns
into its flags (``--seed``).
"""
