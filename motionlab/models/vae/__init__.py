"""Variational autoencoders (chapter 03): an MLP (C)VAE on poses and clips, and a recurrent CVAE.

Modules: :mod:`.model` (the two networks and their configs), :mod:`.losses` (the negative ELBO and the KL
weight), :mod:`.data` (pose vectors, standardised clip windows and the way back to joint positions),
:mod:`.sampling` (clips from prior draws, interpolation between codes), :mod:`.evaluate` (latent use,
plausibility, the benchmark metrics) and :mod:`.experiment` (the chapter's config, its named runs and
``train_all``).
"""
