"""motionlang.datasets — motion-language datasets and text.

* ``sources``: ``--data`` values as ``DataSource`` objects (kind, root, weight, licence), the
  registry of kinds (``KINDS``: prefix, loader, licence), ``load``, the ``Record`` protocol
  and the licence of what is trained on them (``licence_of``, ``non_commercial``)
* ``text``: ``normalize``, ``tokenize``, ``Vocabulary`` (PAD/SOS/EOS/UNK = 0..3)
* ``kitml``: KIT Motion-Language release: ``download_kitml``, ``load_kitml``, ``KitMLRecord``,
  ``load_annotations_tmr``; splits (``random_split``, ``load_split``) from ``splits``
* ``named``: ``cmu35_walkjog`` (Taylor et al. 2006 data), ``mit_walk``
* ``cmu35``: ``load_cmu35`` — CMU subject 35 walk/jog as the CRBM experiment reads it, and
  its per-frame CRBM features (``model_frames``)
* ``custom``: ``load_custom`` — a folder of BVH / ASF-AMC files plus captions
* ``bandai``: the Bandai Namco Research Motion Datasets (``load_bandai``; with English for
  the labels, ``load_bandai_text``; CC BY-NC 4.0); ``bandai_text``: that English grammar and
  the style synonyms
* ``cache``: ``cached`` — an ``.npz`` cache of computed arrays
* ``download``: resumable, checksummed HTTP downloads and safe zip extraction

Submodules are imported explicitly (no import-time work here).
"""
