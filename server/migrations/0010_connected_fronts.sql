-- A cohesive interface's connected failure front and connected softened region (extra
-- crack_tips.csv columns, at the end; docs/run-output-extensions.md). NULL for rows written
-- before: read back as NaN (null).
ALTER TABLE crack_tips ADD COLUMN connected_x REAL;
ALTER TABLE crack_tips ADD COLUMN connected_y REAL;
ALTER TABLE crack_tips ADD COLUMN zone_connected_x REAL;
ALTER TABLE crack_tips ADD COLUMN zone_connected_y REAL;
