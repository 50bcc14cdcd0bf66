-- Whether a job with this id exists.
-- ?1: job id
SELECT id FROM jobs WHERE id = ?1
