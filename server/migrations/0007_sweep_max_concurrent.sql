-- Most jobs of a sweep running at once (`max_concurrent` of `POST /api/v1/sweeps`); NULL:
-- no limit. The claim skips a sweep's queued jobs while that many of its jobs run.
ALTER TABLE sweeps ADD COLUMN max_concurrent INTEGER;
