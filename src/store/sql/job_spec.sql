-- A job's stored spec.
-- ?1: job id
SELECT spec FROM jobs WHERE id = ?1
