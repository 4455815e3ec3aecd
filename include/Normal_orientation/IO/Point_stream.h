// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Point_stream.h
/// \brief Sequential (streaming) reading and writing of point clouds in the `.xyz`,
/// `.pwn` and `.ply` formats, chunk by chunk, with a fixed amount of memory whatever
/// the size of the file: the input and output of the out-of-core orientation.
///
/// `Point_stream_reader` (`Point_stream_reader.h`) reads the same files as
/// `read_point_cloud()` and gives, point by point and bit for bit, the same coordinates
/// and normals, as `Point_record`s numbered 0, 1, ... in file order, with the same error
/// messages. `Point_stream_writer` (`Point_stream_writer.h`) writes records to a
/// `.xyz`/`.pwn` or `.ply` file as they come and makes the file appear, atomically, only
/// when `commit()` is called.

#ifndef NORMAL_ORIENTATION_IO_POINT_STREAM_H
#define NORMAL_ORIENTATION_IO_POINT_STREAM_H

#include <Normal_orientation/IO/Point_cloud_io.h>
#include <Normal_orientation/IO/Point_stream_reader.h>
#include <Normal_orientation/IO/Point_stream_writer.h>

#endif // NORMAL_ORIENTATION_IO_POINT_STREAM_H
