//! OpenVDB float grids (`fgf_io::vdb`): write a C-order `[z][y][x]` array,
//! read one grid back densely.

use crate::errors::io_err;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::path::PathBuf;

#[pyfunction]
fn write_vdb(
    py: Python<'_>,
    path: PathBuf,
    data: PyReadonlyArray3<'_, f32>,
    voxel_size: [f64; 3],
    origin: [f64; 3],
    name: String,
) -> PyResult<()> {
    let s = data.shape();
    let dims = [s[2], s[1], s[0]];
    let v = data.as_slice()?;
    py.detach(|| fgf_io::vdb::write_float_grid(&path, &name, v, dims, voxel_size, origin))
        .map_err(io_err)
}

type ReadOut<'py> = (Bound<'py, PyArray3<f32>>, [i32; 3], [[f64; 4]; 4], f32);

#[pyfunction]
fn read_vdb<'py>(py: Python<'py>, path: PathBuf, grid: String) -> PyResult<ReadOut<'py>> {
    let g = py
        .detach(|| fgf_io::vdb::read_float_grid(&path, &grid))
        .map_err(io_err)?;
    let [nx, ny, nz] = g.dims;
    let a = numpy::ndarray::Array3::from_shape_vec((nz, ny, nx), g.data)
        .expect("dims match the data length");
    Ok((
        a.into_pyarray(py),
        g.index_min,
        g.index_to_world,
        g.background,
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(write_vdb, m)?)?;
    m.add_function(wrap_pyfunction!(read_vdb, m)?)?;
    Ok(())
}
