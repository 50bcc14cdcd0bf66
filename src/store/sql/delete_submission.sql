-- Forgets a submission sbatch refused.
-- ?1: submission id
DELETE FROM submissions WHERE id = ?1
