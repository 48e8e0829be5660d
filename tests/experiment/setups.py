"""What the study's determinism checks compare of a job's result."""


def fingerprint(result):
    return [result.hota.hota.hex(), result.hota.deta.hex(), result.hota.assa.hex(),
            result.gospa.rms.hex(), result.track_count, result.digest]
