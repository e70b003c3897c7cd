"""The projector link, split by job: ``protocol`` (the wire format both ends share),
``client`` (the console's connection), ``supervisor`` (start, adopt, restart the
projector process) and ``service`` (scenes, their needs, status, snapshots)."""
