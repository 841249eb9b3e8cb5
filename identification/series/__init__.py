"""Series of records: Johnson–Cook rate and temperature fits, damage (fracture) fits."""
